// Scenes: TOML files in SI units, read strictly. Every key the program knows is listed once, in
// the table in scene.cpp, with its type, default, allowed range and meaning; `mesopen keys`
// prints that table (docs/scene-keys.md is its copy).
#pragma once

#include "projectile.hpp"
#include "target.hpp"

#include <stdexcept>
#include <string>

namespace mesopen {

struct Scene {
  std::string path;
  TargetSpec target;
  ProjectileSpec projectile;
};

// Bad input: the message names the file, the key, the value and what is allowed. Exit code 2.
class InputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// Read and validate a scene. Throws InputError.
Scene readScene(const std::string &path);

// The reference of every key (Markdown): table, key, type, default, allowed, meaning.
std::string sceneKeysMarkdown();

} // namespace mesopen
