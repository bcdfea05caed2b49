// A scene as the settings of what a run is made of: the FE solver, the contact between the FE
// bodies, the contact between the FE bodies and the disks, and LIGGGHTS's script
// (liggghts-inputs/dem.in). The one place where a scene's keys become those settings.
#pragma once

#include "contact.hpp"
#include "disk_contact.hpp"
#include "scene.hpp"
#include "solver.hpp"

#include <string>
#include <utility>
#include <vector>

namespace mesopen {

// The solver's settings: [run]'s, with `max_dt` (the disks' stable step; infinite without disks).
fem::SolverSettings solverSettings(const Scene &scene, double max_dt);

// Contact of the scene: Coulomb coefficients per pair of materials (0 the projectile's, 1 the
// grains'), the box's left, right and bottom walls when there is a target (`walls`).
fem::ContactSettings contactSettings(const Scene &scene, bool walls);

// The FE bodies' contact with the disks: [contact]'s law, the projectile's friction for body 0 and
// the grains' for the `bodies - 1` others.
coupling::DiskContactSettings diskContactSettings(const Scene &scene, std::size_t bodies);

// The variables of liggghts-inputs/dem.in: the disks' data file `data` (or the LIGGGHTS restart
// file `restart` of a run's checkpoint), the [dem] law, [contact]'s friction between grains, the
// box's walls, the neighbour lists as checkpoints need them (when the scene asks for them).
std::vector<std::pair<std::string, std::string>>
liggghtsVariables(const Scene &scene, const std::string &data, const std::string &restart = "");

} // namespace mesopen
