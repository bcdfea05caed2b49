// Checkpoints of a run, and a run continued from the last one (`mesopen run --resume DIR`).
// With run.checkpoint_interval (wall-clock seconds) or run.checkpoint_time (simulated time) a run
// writes a checkpoint whenever one of them has passed since the last, and one more when SIGINT or
// SIGTERM stops it; a run that completes removes them. Continued from its last checkpoint, a run
// writes the run.h5 it would have written without stopping, byte for byte, on any number of
// threads, in every representation (tests/unit/checkpoint.cpp, tests/liggghts/checkpoint.cpp);
// and a run's results do not depend on when its checkpoints were taken. (With disks, a run that
// takes checkpoints has LIGGGHTS rebuild its neighbour lists at every step: it differs from the
// same scene without checkpoints by round-off.)
// A checkpoint is taken after a step; with disks between two of their windows (one due, or a stop
// asked, within a window waits for its end). It lies in DIR/checkpoint:
//   state.h5                  the run's state (layout in checkpoint.cpp): its scene; the model's
//                             nodes (positions, velocities, forces, masses, external loads),
//                             elements (areas, stresses, energies, plastic strains, viscous
//                             pressures, erosion), boundaries and bodies at rest; the solver's and
//                             the contact's states; the series so far; the frames' times; the
//                             loop's figures
//   journal-NNNNNN.h5j        what was written into run.h5 (its frames) between checkpoints N - 1
//                             and N, as calls to make again (targets/h5_journal.hpp)
//   coupling-NNNNNN-rR.h5     with disks, rank R's coupling state (window count, the forces carried
//                             to the next window, the FE-DEM contact's depths, allowances and
//                             segment grids)
//   liggghts-NNNNNN.restart   with disks, LIGGGHTS's restart file, and in state.h5 the disks' own
//                             forces, which it lacks
// state.h5 is written last, under a temporary name renamed when whole: a checkpoint is whole, or
// the one before stands. A run continued makes its target, model, contact and LIGGGHTS again
// from the checkpoint's scene (the model checked against the checkpoint's by a fingerprint), takes
// the state, and writes run.h5 anew: /mesh, then the journals' calls in order (the same calls
// write the same bytes), then its own frames.
// What is not kept is taken anew, to the same effect: the contact's pair lists (the pairs' order
// is kept), the solver's work ranges, LIGGGHTS's neighbour lists (built at every step when a run
// takes checkpoints, so that its set-up after the restart file builds what a step built:
// liggghts-inputs/dem.in).
// For tests, the environment variable MESOPEN_STOP_AT_STEP=N stops the run after step N as SIGTERM
// would.
#pragma once

#include "h5_journal.hpp"
#include "h5file.hpp"
#include "output.hpp"
#include "run_assembly.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "time_loop.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace mesopen {

// The scene of the last checkpoint in `dir` as its run took it (composed, the seed among its
// keys). Throws InputError naming the file when there is no checkpoint or it is not whole.
Scene checkpointScene(const std::string &dir);

// The LIGGGHTS restart file of the last checkpoint in `dir` ("" without disks); checkpointScene
// said it is whole.
std::string checkpointRestart(const std::string &dir);

// The output directory of a run to continue: its lock taken (DIR/.run.lock, as takeRunDirectory)
// and a run.h5.tmp left by a stop removed; the rest stays until replaced. False when another run
// holds it.
bool takeResumedDirectory(const std::string &dir);

class Checkpoints {
public:
  // For the run in `dir` of `run` (its model and solver as set up from the scene), its series and
  // frames (made, /mesh written into h5), h5 its run.h5 (null on ranks other than 0). A new run
  // removes an earlier run's checkpoints. `resume`: the run continues from the last checkpoint in
  // `dir`: its state taken, run.h5's frames so far written again into h5. Throws InputError for a
  // checkpoint that is not whole or not of this model.
  Checkpoints(const Scene &scene, const std::string &dir, RunAssembly &run, Series &series,
              Frames &frames, H5File *h5, const parallel::World &world, bool resume);
  ~Checkpoints();
  Checkpoints(const Checkpoints &) = delete;
  Checkpoints &operator=(const Checkpoints &) = delete;

  bool on() const { return on_; }
  bool resumed() const { return resumed_; }
  // The loop's figures (element-steps, seconds) and the wall seconds of the run before this
  // process: zero unless it was continued from a checkpoint.
  const LoopResult &before() const { return before_; }
  double wallBefore() const { return wall_before_; }
  std::uint64_t written() const { return number_; } // the last checkpoint's number
  double seconds() const { return seconds_; }       // spent writing them in this process

  // After a step that did not end the run: a checkpoint when one is due, by the simulated time or,
  // with `late` (every process's alike: the clock of rank 0, lateByClock), by the wall clock.
  // `failed`: this process's output of the step failed; it takes part in the checkpoint's gathers
  // (the others wait for it there) and writes nothing.
  void afterStep(const LoopResult &loop, bool late, bool failed);
  // Rank 0's wall clock calls for a checkpoint (run.checkpoint_interval since the last); false
  // on the other ranks.
  bool lateByClock() const;
  // Whether the stop signal every rank agreed on (0: none; the time loop's agreement after each
  // step) lets the run stop after this step: its checkpoint written, when checkpoints are on (with
  // disks false within a window: the loop steps on to its end).
  bool stopBySignal(const LoopResult &loop, int signal);
  // The run ended: completed, its checkpoints are removed; else they stay for --resume.
  void end(bool completed);

private:
  // Every process takes part in each gather whatever failed before; the first failure of this
  // process's files (`failed`: one before the checkpoint) ends its writing and is thrown at the
  // end.
  void write(const LoopResult &loop, bool failed = false);
  void resume();
  void openJournal();
  std::string file(const std::string &stem, std::uint64_t number, const std::string &end) const;

  const Scene &scene_;
  std::string dir_, checkpoint_dir_;
  RunAssembly &run_;
  Series &series_;
  Frames &frames_;
  H5File *h5_;
  const parallel::World &world_;
  bool on_, resumed_;
  std::uint64_t number_ = 0;        // checkpoints written (the last one's number)
  std::uint64_t last_step_ = ~0ull; // the step of the last checkpoint
  std::uint64_t stop_at_ = 0;       // MESOPEN_STOP_AT_STEP, 0: none
  double next_time_ = 0.0;          // simulated time of the next checkpoint
  Clock::time_point last_wall_;     // of the last checkpoint (or the start)
  Clock::time_point start_;         // of this process's part of the run
  LoopResult before_;
  double wall_before_ = 0.0;
  double seconds_ = 0.0;
  std::unique_ptr<H5Journal> journal_; // run.h5's calls since the last checkpoint (rank 0)
};

} // namespace mesopen
