// Names of the scene's enumerations, spelled as in the scene TOML.
#include "solver/scene.hpp"

namespace drape {

const char* to_string(ObstacleShape s) {
  switch (s) {
    case ObstacleShape::Box: return "box";
    case ObstacleShape::Sphere: return "sphere";
    case ObstacleShape::None: return "none";
    case ObstacleShape::Disc: return "disc";
  }
  return "?";
}

const char* to_string(ClothShape s) {
  switch (s) {
    case ClothShape::Square: return "square";
    case ClothShape::Disc: return "disc";
  }
  return "?";
}

const char* to_string(GradientMode g) {
  switch (g) {
    case GradientMode::Analytic: return "analytic";
    case GradientMode::Numeric: return "numeric";
  }
  return "?";
}

const char* to_string(Schedule s) {
  switch (s) {
    case Schedule::ActiveLists: return "active-lists";
    case Schedule::Static: return "static";
    case Schedule::Dynamic: return "dynamic";
    case Schedule::Guided: return "guided";
  }
  return "?";
}

const char* to_string(SolverMethod m) {
  switch (m) {
    case SolverMethod::Newton: return "newton";
    case SolverMethod::Cg: return "cg";
  }
  return "?";
}

const char* to_string(Preconditioner p) {
  switch (p) {
    case Preconditioner::Jacobi: return "jacobi";
    case Preconditioner::Multigrid: return "multigrid";
    case Preconditioner::Auto: return "auto";
  }
  return "?";
}

const char* to_string(Prediction p) {
  switch (p) {
    case Prediction::Fall: return "fall";
    case Prediction::Rest: return "rest";
    case Prediction::Cheaper: return "cheaper";
  }
  return "?";
}

Preconditioner stage_preconditioner(const SolverSpec& s, int64_t particles) {
  if (s.preconditioner != Preconditioner::Auto) return s.preconditioner;
  return particles >= s.multigrid_particles ? Preconditioner::Multigrid : Preconditioner::Jacobi;
}

SolverSpec stage_solver(const SolverSpec& s, int64_t particles) {
  SolverSpec t = s;
  t.preconditioner = stage_preconditioner(s, particles);
  if (s.preconditioner == Preconditioner::Auto && t.preconditioner == Preconditioner::Multigrid) {
    t.dt_max = s.multigrid_dt_max;
    t.max_iterations = s.multigrid_max_iterations;
  }
  return t;
}

const char* to_string(AmrcIndicator i) {
  switch (i) {
    case AmrcIndicator::Angle: return "angle";
    case AmrcIndicator::Deflection: return "deflection";
  }
  return "?";
}

}  // namespace drape
