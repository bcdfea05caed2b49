"""CTest robustness_full_disk (label robustness): `mesopen target` and `mesopen run` on a disk that
fills up end with exit 1, a message and a failed summary.json, leave every file they wrote whole
(or not at all), and are not ended by a signal.

The full disk is the file-size limit (RLIMIT_FSIZE, SIGXFSZ ignored): a write past it fails with
EFBIG as it would with ENOSPC, without mounting a small file system (which needs privileges).
Cases, each failing before its fix:
  - target: target.vtu was renamed into place cut short (VTK's writer returns 1 after a failed
    write); now the error code is read and the file is not renamed (with target.h5, written beside
    it, past the limit too);
  - run with VTK frames: the limit ends the run cleanly (exit 1), the frames written are whole;
  - run whose run.h5 outgrows the limit: the failed close left HDF5's exit handler a half-closed
    file, and the process crashed (SIGSEGV) after writing its failed summary.

    full_disk.py MESOPEN SCRATCH_DIR
"""
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import h5py

TARGET = """[target]
width = 1.5e-3
height = 0.6e-3
diameter = 60e-6
"""

RUN = """[target]
width = 1.0e-3
height = 0.5e-3
diameter = 60e-6
mesh_size = 15e-6
[projectile]
length = 0.3e-3
[run]
end_time = 2e-7
frame_interval = 1e-8
"""

def limited(limit):
    """A pre-exec function: files of at most `limit` bytes."""
    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


def whole(path):
    """Why the file at `path` does not open whole, or None."""
    try:
        if path.endswith(".h5"):
            with h5py.File(path, "r") as h5:
                h5.visititems(lambda name, item: item[()] if isinstance(item, h5py.Dataset) else None)
        elif path.endswith(".json"):
            with open(path) as f:
                json.load(f)
        elif path.endswith(".pvd"):
            ElementTree.parse(path)
        elif path.endswith(".vtu"):  # raw appended data is not XML: the file must end as written
            with open(path, "rb") as f:
                f.seek(max(os.path.getsize(path) - 64, 0))
                if not f.read().rstrip().endswith(b"</AppendedData>\n</VTKFile>"):
                    return "cut short"
        elif path.endswith(".tmp"):
            return "a temporary file left behind"
    except Exception as e:  # any failure to read it is the finding
        return str(e)[:200]
    return None


def main():
    mesopen, scratch = sys.argv[1], sys.argv[2]
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    failures = []
    # The target's files (target.h5 757 kB, target.vtu 471 kB compressed) are written side by
    # side: both pass 256 kB, and the first to fail is named.
    for name, command, scene, want, limit in [
            ("target", "target", TARGET, ".tmp", 256 << 10),
            ("run-vtk-frames", "run", RUN, ".tmp", 1 << 20),
            ("run-h5", "run", RUN + "vtk = false\n", "run.h5.tmp", 1 << 20)]:
        path = os.path.join(scratch, name + ".toml")
        with open(path, "w") as f:
            f.write(scene)
        out = os.path.join(scratch, name)
        p = subprocess.run([mesopen, command, path, "-o", out, "--threads", "1"] +
                           (["--quiet"] if command == "run" else []),
                           capture_output=True, text=True, timeout=120, preexec_fn=limited(limit))
        message = (p.stdout + p.stderr).strip().splitlines()
        print("%s: exit %d; %s" % (name, p.returncode, message[-1] if message else ""))
        if p.returncode != 1 or not any(want in line for line in message):
            failures.append("%s: exit %d (want 1, a message naming %s): %s" %
                            (name, p.returncode, want, "\n".join(message[-3:])))
        try:
            with open(os.path.join(out, "summary.json")) as f:
                status = json.load(f).get("status")
        except (OSError, ValueError) as e:
            status = "unreadable: %s" % e
        if status != "failed":
            failures.append("%s: summary.json status %s (want failed)" % (name, status))
        for folder, _, files in os.walk(out):
            for file in files:
                why = whole(os.path.join(folder, file))
                if why:
                    failures.append("%s: %s does not open whole: %s" % (name, file, why))
    for f in failures:
        print("FAIL: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
