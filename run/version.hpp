// The program's version: the project's version and `git describe` at build time (with "-dirty"
// when the tree had uncommitted changes), e.g. "0.1.0 (git ed9f2aa)". Recorded in every run's
// run.h5 and summary.json, printed by `mesopen --version`.
#pragma once

namespace mesopen {

const char *programVersion();

} // namespace mesopen
