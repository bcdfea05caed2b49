// Campaigns (docs/campaign.md): a list of runs, each a scene file with keys set on top of it, each
// repeated on several target layouts (replicates: target.seed + k * seed_stride), run one after
// another by `mesopen campaign`; their measures of instability tabulated per run with 95 %
// confidence intervals, and trends between runs tested.
#pragma once

#include "scene.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mesopen {

struct CampaignRun {
  std::string name, label;
  std::string scene;                       // the scene file it starts from
  toml::table set;                         // scene keys set on top of it, as scene tables
  std::map<std::string, double> reference; // published figures by measure (thesis Table 5.1)
};

// What a trend expects of the measure's magnitude |m| over its runs, in their order: to rise or
// fall with the parameter x, to differ between the runs, or to stay alike.
enum class TrendKind { rises, falls, differs, similar };
inline constexpr Named<TrendKind> trend_kind_names[] = {{"rises", TrendKind::rises},
                                                        {"falls", TrendKind::falls},
                                                        {"differs", TrendKind::differs},
                                                        {"similar", TrendKind::similar}};

struct Trend {
  std::string name;
  std::string measure = "max_abs_rotational_momentum";
  TrendKind expect = TrendKind::rises;
  std::vector<std::string> runs; // in the order of the parameter
  std::vector<double> x;         // the parameter's value per run, increasing (default 1, 2, ...)
  double tolerance = NAN;        // similar: the largest difference that counts as alike, as a
                                 // fraction of the mean of |m| over the runs
};

struct Campaign {
  std::string path, name;
  std::optional<Representation> representation; // overrides every scene's run.representation
  int replicates = 1;
  std::int64_t seed_stride = 1000;
  bool frames = false; // keep the scenes' frames (default: series only)
  std::vector<CampaignRun> runs;
  std::vector<Trend> trends;
};

// The measures a campaign tabulates (names of instability.json's figures) and how they print.
struct CampaignMeasure {
  const char *name, *title, *unit;
};
inline constexpr CampaignMeasure campaign_measures[] = {
    {"average_lateral_force", "average lateral force", "N/m"},
    {"lateral_displacement", "lateral displacement", "m"},
    {"max_abs_rotational_momentum", "peak rotational momentum", "kg m^2/s per m"},
    {"tilt", "tilt", "rad"},
    {"final_depth_over_length", "depth", "lengths"}};

// Reads and checks a campaign file; every run's scene is composed and read as `mesopen run` would
// (so that a bad key fails before anything runs). Throws InputError naming file, key and value.
Campaign readCampaign(const std::string &path);

// The scene of replicate k (from 0) of a run, as TOML text: its scene file with the run's keys set,
// target.seed + k seed_stride, the campaign's representation, and frame_interval = 0 unless the
// campaign keeps frames.
std::string composeScene(const Campaign &campaign, const CampaignRun &run, int replicate);

// Statistics. The two-sided 95 % quantile of Student's t with `dof` degrees of freedom (dof >= 1).
double studentT95(int dof);

// Mean and the half-width of its 95 % confidence interval, t(n-1) s / sqrt(n) (NaN below n = 2).
struct Estimate {
  double mean = NAN, half_width = NAN, sd = NAN;
  int n = 0;
};
Estimate estimate(const std::vector<double> &values);

// A trend's test on the magnitudes |m| of its runs' replicates (values[r]: run r's).
//   rises / falls: least-squares slope of |m| against x over every replicate, with its 95 %
//     interval t(n-2) s_e / sqrt(Sxx): confirmed if the interval lies on the expected side of 0,
//     reversed if on the other, else not confirmed;
//   differs: the same slope between two runs (x = 0, 1: the difference of means, pooled variance):
//     confirmed if the interval excludes 0;
//   similar: an equivalence test over every pair of runs (intersection-union, two one-sided tests
//     at 2.5 % each): confirmed if every pair's 95 % interval lies within +-tolerance times the
//     mean of |m| over the runs; reversed if some pair's interval lies wholly beyond it (the runs
//     differ); else not confirmed (too few replicates to tell).
// Not tested with fewer than two replicates in some run. `effect` is the slope (per unit of x),
// the difference, or the pair's difference that decided (similar: the farthest interval end), with
// its interval's half-width.
struct TrendResult {
  std::string verdict; // confirmed, not confirmed, reversed, not tested
  double effect = NAN, half_width = NAN;
  std::string seen; // the means' direction with x: rises, falls (each step), rises overall, falls
                    // overall (first to last), flat, n/a (a run without results)
  std::vector<Estimate> magnitudes; // of |m|, per run
};
TrendResult testTrend(const Trend &trend, const std::vector<std::vector<double>> &values);

} // namespace mesopen
