#pragma once
// Every scene key, declared once (scene_schema.cpp).
#include "io/parameters.hpp"

namespace drape {

const ParameterList& scene_parameters();

}  // namespace drape
