#!/usr/bin/env bash
# CTest yade_spheres_at_rest (label yade): mesopen's target.spheres loads in YADE and sits still.
#
#   spheres_at_rest.sh MESOPEN SCRATCH_DIR
#
# Makes a small target (1.5 x 1.0 mm, 42-78 um grains, 30 % porosity, about 370 grains) with
# `mesopen target`, then runs spheres_at_rest.py in YADE (yade -n -x, no GUI) twice:
#   1. the file as written: its radii are the DEM disks' radii, which overlap neither each other nor
#      the walls x = 0, x = width, y = 0, so after 100 steps with no gravity no sphere may be faster
#      than 1 m/s (the tolerance and its reason are in spheres_at_rest.py);
#   2. a negative control: the same spheres with radii x 1.15 must be caught (faster than 1 m/s), so
#      the check can fail.
# YADE is the Debian package `yade`, installed by tools/setup.sh; without it the test fails.
set -euo pipefail

if [ "$#" -ne 2 ]; then
  echo "usage: $0 MESOPEN SCRATCH_DIR" >&2
  exit 2
fi
mesopen="$1"
scratch="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

if ! command -v yade >/dev/null 2>&1; then
  echo "FAIL: yade is not on PATH; install the Debian package 'yade' (bash tools/setup.sh does)" >&2
  exit 1
fi

rm -rf "$scratch"
mkdir -p "$scratch"
width=1.5e-3
cat >"$scratch/scene.toml" <<TOML
[target]
width = $width
height = 1.0e-3
diameter = [42e-6, 78e-6]
porosity = 0.30
seed = 1

[projectile]
enabled = false
TOML
"$mesopen" target "$scratch/scene.toml" -o "$scratch/target" --no-mesh --no-plot --threads 2
spheres="$scratch/target/target.spheres"

# yade -n -x SCRIPT ARGS: batch mode, exits with the script's status. Its banner lines (the local
# TCP/XMLRPC servers it always opens) are dropped from the log. YADE writes an IPython profile in
# $HOME: give it one in the scratch dir.
mkdir -p "$scratch/home"
run_yade() {
  HOME="$scratch/home" \
    yade -n -x "$here/spheres_at_rest.py" "$spheres" --width "$width" "$@" 2>&1 |
    grep -v -e '^TCP python prompt' -e '^XMLRPC info provider'
  return "${PIPESTATUS[0]}"
}

echo "== $spheres as written: expect no sphere faster than 1 m/s"
status=0
run_yade || status=$?
if [ "$status" -ne 0 ]; then
  echo "FAIL: the spheres of $spheres move (or yade failed, status $status)"
  exit 1
fi

echo "== negative control: radii x 1.15 must overlap and move faster than 1 m/s"
status=0
log="$(run_yade --radius-scale 1.15)" || status=$?
echo "$log"
if [ "$status" -ne 1 ] || ! grep -q '^FAIL: a sphere moves at' <<<"$log"; then
  echo "FAIL: the negative control was not caught (yade status $status): the check cannot fail"
  exit 1
fi
echo "OK: $spheres is at rest in YADE, and the overlapping control is caught"
