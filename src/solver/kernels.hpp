#pragma once
// Per-element kinematics, one file per element kind (elements/*_K.hpp),
// kept apart from the Evaluator's loops that drive them (AMReX style). Each
// kernel returns the element's kinematic measure k (edge length, bending
// angle, shear angle) and writes dk/dx for each of its particles; the
// *_hv kernels also its derivative along a direction (hand-derived; the
// templated kernels on Dual are their reference); the product and diagonal
// kernels read the numbers Newton's linear solve keeps (kept_K for triples
// and cells).
#include "solver/elements/band_K.hpp"
#include "solver/elements/edge_K.hpp"
#include "solver/elements/kept_K.hpp"
#include "solver/elements/shear_K.hpp"
#include "solver/elements/triple_K.hpp"
#include "solver/elements/v3.hpp"
