#pragma once
// Scene configuration: TOML file + --set overrides -> validated Scene.
// Strict: unknown keys, wrong types, out-of-range values and missing files
// are refused with an InputError naming the key (and file:line where known).
#include <optional>
#include <string>
#include <vector>

#include "solver/scene.hpp"

namespace drape {

// `path`: TOML file, or none for the embedded default scene.
// `overrides`: "section.key=value" strings, value in TOML syntax
// (numbers, true/false, [a, b], quoted or bare strings).
Scene load_scene(const std::optional<std::string>& path,
                 const std::vector<std::string>& overrides);

// The same from TOML text (a checkpoint's scene); `origin` names it in errors.
Scene load_scene_text(const std::string& toml, const std::string& origin,
                      const std::vector<std::string>& overrides);

// Refuses --set keys that a restart must not change (InputError).
void check_restart_overrides(const std::vector<std::string>& overrides);
// Whether one of the --set overrides (key=value) sets `key`.
bool overrides_key(const std::vector<std::string>& overrides, const std::string& key);

// Refuses a cloth whose particle mass (the fabric's areal density times the
// area per particle) is not a finite positive number; the scene and the
// fabric are each valid alone, so only together can this be checked.
void check_particle_mass(const Scene& s, double density, const std::string& fabric);

// The resolved scene as TOML text (what --dry-run prints; also stored in outputs).
std::string scene_to_toml(const Scene& s);

// The reference of every scene key as markdown tables (key, default, unit,
// allowed values, meaning): what docs/configuration.md shows.
std::string scene_reference();

}  // namespace drape
