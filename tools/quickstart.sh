#!/usr/bin/env bash
# Set up (Debian 12: installs missing packages), build in build/, make the default target
# (examples/targets/baseline.toml) in out/baseline, and say where the results are.
set -euo pipefail

# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

mesopen_install
mesopen_build

cd "$MESOPEN_ROOT"
build/bin/mesopen target examples/targets/baseline.toml -o out/baseline

out="$MESOPEN_ROOT/out/baseline"
plot="grain-sizes.png   grain-size histogram"
if [ ! -f "$out/grain-sizes.png" ]; then
  plot="grain-sizes.png   not made (see the warning above; needs /usr/bin/python3 with matplotlib)"
fi
cat <<EOF

Results are in $out:
  target.vtu        grains and projectile: open in ParaView
  target.h5         everything (sites, grain polygons, mesh, projectile)
  target.json       grains, porosity, mean/std diameter, timings
  $plot
  (also target.data for LIGGGHTS, target.spheres for YADE, summary.json)

The simulator (mesopen run) comes in a later version.
EOF
