// A run's files beside run.h5's series and frames (run_output.hpp): its output directory taken and
// cleared, run.h5's attributes, summary.json.
#pragma once

#include "h5file.hpp"
#include "run_assembly.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "time_loop.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace mesopen {

// The output directory taken for a run and cleared of an earlier run's files (frames included).
// Its lock, DIR/.run.lock, is held to the end of the process: a second run into the directory
// would remove this one's run.h5.tmp and frames. False when another run holds it. Throws
// InputError when the directory cannot be made or holds another command's output.
bool takeRunDirectory(const Scene &scene, const std::string &dir);

// The attributes of run.h5's root: format, version, program (the program's version), status,
// representation, scene (composed: every key at its value), seed, velocity, spin, end_time,
// projectile_length, and obliquity, yaw and offset when not 0; the materials' resolved
// parameters in /materials/{projectile, grains}.
void writeRunAttributes(H5File &h5, const Scene &scene, const std::string &status);

// The census of multiple time stepping's levels (run.level_census_interval) into run.h5's /levels,
// a dataset per column (fem::LevelCensus::columns).
void writeLevels(H5File &h5, const fem::LevelCensus &census);
// Its figures for summary.json, per largest level L: the shares of the active element-steps by
// level (the bodies' own, and with the rings promoted), the ring, the pairs by their two levels,
// the element and pair work against single rate, and the projected cost ratio
//   R = (1 - s_c) W_e,MTS / W_e + s_c W_p,MTS / W_p,
// s_c the contact's share of the steps' wall time (the unit costs of an element update and a pair
// update from the run's own timing), W the summed work of the samples.
nlohmann::json levelFigures(const fem::LevelCensus &census, const LoopResult &loop,
                            const fem::Contact *contact);

// The disks' figures over all ranks (every rank takes part): disks, contacts with the FE bodies,
// work on the disks, windows.
nlohmann::json demFigures(const RunAssembly &run, const parallel::World &world);

// What each rank measured of its own part of the run, in rank order: over the steps it took
// (`steps`, not those before a checkpoint) the bytes it received from the others within the
// steps, the most within one step, the collective operations within them, the bytes it received
// in the time loop outside the steps (LoopResult), the pairs of bodies its contact searched
// (fem::ContactStatistics::pair_steps; 0 without contact), and its peak resident memory (VmHWM of
// /proc/self/status; -1 where it cannot be read); and the contact's statistics of all ranks
// together (fem::Contact::statisticsOfAll).
struct RankFigures {
  std::size_t steps = 0;
  std::vector<std::int64_t> step_bytes, max_step_bytes, step_operations, step_messages, other_bytes,
      contact_pair_steps, peak_memory_bytes, halo_node_steps;
  fem::ContactStatistics contact;
};
// This process's figures gathered from every process (every process calls it).
RankFigures rankFigures(const RunAssembly &run, const LoopResult &loop);

// How the element work was shared by the ranks (fem::PartitionReport) and what each rank's part
// cost it (`ranks`), for summary.json: per rank, per step, the active elements and nodes it owned,
// its halo nodes (the other ranks' nodes whose positions and velocities it receives from their
// owners: the boundary nodes its contact pairs need, or every moving node it does not own when a
// force provider reads every node, the FE-DEM coupling), the
// pairs of bodies its contact searched, the bytes it received; its peak memory.
nlohmann::json partitionSummary(const fem::PartitionReport &partition, const RankFigures &ranks);

// summary.json: what ran, how it ended, its figures and files (the element work's partition
// among them and each rank's figures, `rank_figures`); `dem` the disks' figures (null: no disks),
// `ranks` the MPI ranks.
nlohmann::json runSummary(const Scene &scene, const RunAssembly &run, const Series &series,
                          const Frames &frames, const LoopResult &loop, double wall, int ranks,
                          const RankFigures &rank_figures, const nlohmann::json &dem);

// summary.json of a run that ended before its time loop (`status` "interrupted" or "failed"):
// the scene, the status and why.
void writeUnstartedSummary(const std::string &dir, const std::string &scene_path,
                           const std::string &status, const std::string &failure);

} // namespace mesopen
