#include "generator.hpp"

#include "mesh.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace mesopen {

namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The sites inside [0, w] x [0, h], grains first.
Sites window(const Sites &s, double w, double h) {
  Sites out;
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t i = pass == 0 ? 0 : s.grains; i < (pass == 0 ? s.grains : s.size()); ++i)
      if (s.x[i] <= w && s.y[i] <= h) {
        out.x.push_back(s.x[i]), out.y.push_back(s.y[i]), out.r.push_back(s.r[i]);
        out.grains += pass == 0;
      }
  return out;
}

} // namespace

double calibrateVoidFactor(const Sites &placed, const TargetSpec &spec, GeneratorReport &report,
                           std::vector<Tessellated> *trials) {
  TargetSpec trial = spec;
  Sites sites = placed;
  const double limit = 20000.0;
  if (placed.grains > limit) {
    const double shrink = std::sqrt(limit / placed.grains);
    trial.width = spec.width * shrink, trial.height = spec.height * shrink;
    sites = window(placed, trial.width, trial.height);
    trials = nullptr; // a window's tessellations are not the target's
  }
  auto porosity = [&](double factor) {
    Tessellated t{factor, sites, {}, {}, {}};
    t.grains = tessellate(t.sites, trial, factor, t.grain_site, t.report);
    double solid = 0.0;
    for (double a : grainFigures(t.grains).area)
      solid += a;
    if (trials)
      trials->push_back(std::move(t));
    const double p = 1.0 - solid / trial.area();
    report.trial_factor.push_back(factor);
    report.trial_porosity.push_back(p);
    return p - spec.porosity;
  };
  // Porosity grows with the void factor (with power cells always; with relaxed Voronoi cells
  // until inverted cells make the repairs remove voids wholesale). Bracket the request, widening
  // while the porosity comes closer, then regula falsi (Illinois).
  double a = 1.0, fa = porosity(a);
  double b = fa > 0 ? 0.7 : 1.4, fb = porosity(b);
  for (int k = 0; k < 5 && fa * fb > 0 && std::abs(fb) < std::abs(fa); ++k) {
    a = b, fa = fb;
    b = fa > 0 ? b * 0.7 : b * 1.4;
    fb = porosity(b);
  }
  if (fa * fb > 0)
    return std::abs(fa) < std::abs(fb) ? a : b; // out of reach: the closest
  int side = 0;
  for (int k = 0; k < 10; ++k) {
    const double c = (a * fb - b * fa) / (fb - fa), fc = porosity(c);
    if (std::abs(fc) < 2e-4)
      return c;
    if (fc * fb > 0) {
      b = c, fb = fc;
      if (side == -1)
        fa *= 0.5;
      side = -1;
    } else {
      a = c, fa = fc;
      if (side == 1)
        fb *= 0.5;
      side = 1;
    }
  }
  return std::abs(fa) < std::abs(fb) ? a : b;
}

Target generateTarget(const TargetSpec &spec, GeneratorReport &report,
                      const std::function<void(const std::string &)> &progress) {
  auto say = [&](const std::string &what) {
    if (progress)
      progress(what);
  };
  Target t;
  t.spec = spec;
  auto t0 = std::chrono::steady_clock::now();
  t.sites = initialSites(spec, spec.void_scale);
  report.grain_sites = t.sites.grains;
  report.void_sites = t.sites.size() - t.sites.grains;
  report.placement = relaxSites(t.sites, spec, [&](int it, int most, double energy) {
    if (!progress)
      return;
    const double elapsed = since(t0);
    char line[160];
    std::snprintf(line, sizeof line,
                  "placing %zu sites: iteration %d/%d, overlap %.1e of start, ETA %.0f s",
                  t.sites.size(), it, most, energy, elapsed / it * (most - it));
    progress(line);
  });
  report.seconds_sites = since(t0);
  say("porosity control");

  t0 = std::chrono::steady_clock::now();
  std::vector<Tessellated> trials;
  report.void_factor =
      spec.calibrate_porosity ? calibrateVoidFactor(t.sites, spec, report, &trials) : 1.0;
  report.seconds_calibration = since(t0);

  say("tessellation");
  t0 = std::chrono::steady_clock::now();
  const auto found = std::find_if(trials.begin(), trials.end(), [&](const Tessellated &trial) {
    return trial.void_factor == report.void_factor;
  });
  if (found != trials.end()) { // the calibration's trial with the factor found
    t.sites = std::move(found->sites), t.grains = std::move(found->grains);
    t.grain_site = std::move(found->grain_site), report.tessellation = std::move(found->report);
  } else
    t.grains = tessellate(t.sites, spec, report.void_factor, t.grain_site, report.tessellation);
  report.seconds_tessellation = since(t0);

  if (spec.mesh != MeshKind::none)
    say("meshing " + std::to_string(t.grains.size()) + " grains");
  t0 = std::chrono::steady_clock::now();
  t.mesh = meshGrains(t.grains, spec.mesh, spec.mesh_size, spec.min_angle);
  report.seconds_mesh = since(t0);
  return t;
}

} // namespace mesopen
