#!/usr/bin/env bash
# Set up (Debian 12: installs missing packages), build in build/, run the reduced default
# penetration scene (examples/quickstart.toml: target, projectile, contact; a few minutes) in
# out/quickstart, and say where the results are.
set -euo pipefail

# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

mesopen_install
mesopen_build

cd "$MESOPEN_ROOT"
build/bin/mesopen run examples/quickstart.toml -o out/quickstart

out="$MESOPEN_ROOT/out/quickstart"
cat <<EOF

Results are in $out:
  vtk/run.pvd       the frames (grains and projectile: stresses, pressure, plastic strain,
                    velocities): open in ParaView
  run.h5            the projectile's series (depth, rotational momentum, lateral force, tilt),
                    the energies, and the frames
  summary.json      what ran, how it ended, wall time, contact figures

The thesis's runs: examples/baseline.toml (run 6) and examples/thesis/*.toml. A target alone:
  build/bin/mesopen target examples/targets/baseline.toml -o out/baseline
EOF
