// Compiles against the installed headers and links the installed drape::core.
#include <cstring>
#include <iostream>

#include "solver/scene.hpp"

int main() {
  const char* name = drape::to_string(drape::SolverMethod::Newton);
  std::cout << name << "\n";
  return std::strcmp(name, "newton") == 0 ? 0 : 1;
}
