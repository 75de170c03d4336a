// libFuzzer harness: the scene parser with --set overrides. The input is a
// scene TOML, optionally followed by a line "%%" and up to 8 override lines
// ("section.key=value"). Bad input must end in InputError, never a crash,
// a sanitizer report or a hang; a scene that loads must also print.
#include <cstdint>

#include "fuzz/split.hpp"
#include "io/config.hpp"
#include "base/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const drape::fuzz::Parts parts = drape::fuzz::split_at_marker(data, size, "%%");
  const std::vector<std::string> overrides = drape::fuzz::lines_of(parts.tail, 8);
  try {
    const drape::Scene scene = drape::load_scene_text(parts.head, "fuzz.toml", overrides);
    drape::check_particle_mass(scene, 0.3, "fuzz");
    (void)drape::scene_to_toml(scene);
  } catch (const drape::InputError&) {
  }
  return 0;
}
