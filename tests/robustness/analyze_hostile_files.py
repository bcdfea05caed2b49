"""CTest robustness_analyze_hostile_files (label robustness): `mesopen analyze` on damaged or
hostile run.h5 files ends cleanly, with exit 2 and a message, within seconds.

A tiny run's run.h5 is made with `mesopen run`, then copied and altered with h5py:
  - /series/time declaring 2^40 elements (a few KB on disk): it was allocated and aborted the
    process with bad_alloc; now refused (exit 2, "declares ... elements");
  - /series/time declaring 2^31 x 2^31 elements: aborted with length_error; now refused (a
    series has one dimension);
  - /series/time spanning 1e-320 s (denormal steps): the spectrum's frequency loop never ended;
    now analyze completes (exit 0) in well under the 60 s allowed here;
  - a series all NaN, a 2-D /series/time, a zero projectile length: accepted quietly before (and
    measures made of them); now refused (exit 2) with what is wrong.
  - an earlier plot that cannot be removed (a directory where a plot was, standing in for a
    directory the user cannot write, which a test run as root cannot make): the uncaught
    filesystem_error aborted analyze; now refused (exit 2) naming the file, the plots kept.
Each case must end by an exit code, not a signal, and within its time limit.

    analyze_hostile_files.py MESOPEN SCRATCH_DIR
"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

SCENE = """[target]
width = 0.6e-3
height = 0.3e-3
diameter = 60e-6
mesh_size = 15e-6
[projectile]
length = 0.3e-3
[run]
end_time = 5e-8
frame_interval = 0
"""


def analyze(mesopen, run_dir, limit):
    try:
        p = subprocess.run([mesopen, "analyze", run_dir, "--no-plot"], capture_output=True,
                           text=True, timeout=limit)
    except subprocess.TimeoutExpired:
        return None, "did not end within %d s" % limit
    return p.returncode, p.stdout + p.stderr


def main():
    mesopen, scratch = sys.argv[1], sys.argv[2]
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    with open(os.path.join(scratch, "scene.toml"), "w") as f:
        f.write(SCENE)
    base = os.path.join(scratch, "base")
    subprocess.run([mesopen, "run", os.path.join(scratch, "scene.toml"), "-o", base, "--quiet"],
                   check=True, stdout=subprocess.DEVNULL)

    def altered(name, change):
        d = os.path.join(scratch, name)
        os.makedirs(d)
        shutil.copyfile(os.path.join(base, "run.h5"), os.path.join(d, "run.h5"))
        with h5py.File(os.path.join(d, "run.h5"), "r+") as h5:
            change(h5)
        return d

    def huge(shape):
        def change(h5):
            del h5["series/time"]
            # declared, not written (chunked: HDF5 stores no chunk never written)
            h5.create_dataset("series/time", shape=shape, dtype="f8",
                              chunks=(1,) * (len(shape) - 1) + (1024,))
        return change

    def tiny_times(h5):
        n = h5["series/time"].shape[0]
        del h5["series/time"]
        h5["series/time"] = np.arange(n, dtype="f8") * 5e-324

    def all_nan(h5):
        h5["series/projectile/tilt"][...] = np.nan

    def two_d_time(h5):
        t = h5["series/time"][:]
        del h5["series/time"]
        h5["series/time"] = np.stack([t, t])

    def zero_length(h5):
        h5.attrs["projectile_length"] = 0.0

    failures = []
    for name, change, want, text in [
            ("all-nan", all_nan, 2, "holds no finite value"),
            ("2d-time", two_d_time, 2, "dimensions; allowed: 1"),
            ("zero-length", zero_length, 2, "projectile's length is 0"),
            ("huge-1d", huge((2 ** 40,)), 2, "declares"),
            ("huge-2d", huge((2 ** 31, 2 ** 31)), 2, "dimensions; allowed: 1"),
            ("denormal-time", tiny_times, 0, "")]:
        d = altered(name, change)
        code, output = analyze(mesopen, d, 60)
        print("%s: exit %s; %s" % (name, code, output.strip().splitlines()[-1] if output.strip() else ""))
        if code != want or (text and text not in output):
            failures.append("%s: exit %s (want %d%s): %s" % (
                name, code, want, ", a message with '%s'" % text if text else "", output[-300:]))
    # An earlier plot analyze cannot remove.
    d = altered("stuck-plot", lambda h5: None)
    os.makedirs(os.path.join(d, "instability-tilt.png", "inside"))
    code, output = analyze(mesopen, d, 60)
    print("stuck-plot: exit %s; %s" % (code, output.strip().splitlines()[-1] if output.strip() else ""))
    if code != 2 or "cannot remove an earlier plot, instability-tilt.png" not in output:
        failures.append("stuck-plot: exit %s (want 2, naming the plot): %s" % (code, output[-300:]))
    for f in failures:
        print("FAIL: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
