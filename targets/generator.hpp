// The target generator end to end (thesis section 4.2): sites, placement, tessellation, meshes.
// Equations: docs/models.md §10.4.
#pragma once

#include "measures.hpp"
#include "sites.hpp"
#include "target.hpp"
#include "tessellation.hpp"

#include <functional>
#include <string>
#include <vector>

namespace mesopen {

struct GeneratorReport {
  PlacementReport placement;
  TessellationReport tessellation;
  std::size_t grain_sites = 0, void_sites = 0; // as placed
  double void_factor = 1.0;                    // void radii in the tessellation over their own
  std::vector<double> trial_factor, trial_porosity;
  double seconds_sites = 0, seconds_calibration = 0, seconds_tessellation = 0, seconds_mesh = 0;
};

// Porosity control. The void sites' number and size set the porosity (thesis 4.2.1), but how much
// of the space between grain disks their cells take depends on the placement and the
// tessellation. With calibrate_porosity the tessellation scales the void radii by a factor found
// by safeguarded secant steps so that the porosity matches the request: on the placed sites
// themselves, or for more than 20,000 grains on a corner window of them holding about 20,000.
// On the placed sites themselves, each trial's tessellation is appended to `trials` if given (the
// one with the factor found is the target's: it need not be made again).
struct Tessellated {
  double void_factor = 1.0;
  Sites sites; // as the tessellation left them
  Polygons grains;
  std::vector<std::uint32_t> grain_site;
  TessellationReport report;
};
double calibrateVoidFactor(const Sites &placed, const TargetSpec &spec, GeneratorReport &report,
                           std::vector<Tessellated> *trials = nullptr);

// Make the target the spec asks for. Deterministic: the same spec gives the same target for any
// number of threads.
// `progress`, when given, hears what the generator is doing (a phase, or a placement iteration).
Target generateTarget(const TargetSpec &spec, GeneratorReport &report,
                      const std::function<void(const std::string &)> &progress = {});

} // namespace mesopen
