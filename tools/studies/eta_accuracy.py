#!/usr/bin/python3
"""How close the time left that `mesopen run` estimates is to the time that was left.

Reads the log of each run directory given (DIR/mesopen.log): its progress lines (one per 5 % of
the run, each with the estimate, `ETA`), the start of the time loop and the run's end. For each
progress line in the last half of the loop it prints the estimate, the time that was left and the
relative error; the summary line gives the worst error over the lines with at least 5 % of the
loop's time still to go (closer to the end a second is a large share of what is left).

    /usr/bin/python3 tools/studies/eta_accuracy.py RUN_DIR...
Exit code 1 when a log has no completed run.
"""
import re
import sys

STAMP = re.compile(r"^\[\s*([0-9.]+) s\] (.*)$")


def read_log(path):
    start = end = None
    estimates = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            m = STAMP.match(line.rstrip("\n"))
            if not m:
                continue
            wall, text = float(m.group(1)), m.group(2)
            if "the time loop starts" in text:
                start = wall
            elif text.startswith("completed:"):
                end = wall
            elif " ETA " in text:
                estimates.append((wall, float(text.rsplit(" ETA ", 1)[1].split()[0])))
    return start, end, estimates


def main(dirs):
    status = 0
    for d in dirs:
        start, end, estimates = read_log(d + "/mesopen.log")
        if start is None or end is None:
            print("%s: no completed run in mesopen.log" % d)
            status = 1
            continue
        loop = end - start
        print("%s: time loop %.1f s" % (d, loop))
        print("  %8s %10s %10s %8s" % ("at [s]", "ETA [s]", "left [s]", "error"))
        worst = 0.0
        for wall, eta in estimates:
            if wall - start < 0.5 * loop:
                continue
            left = end - wall
            error = (eta - left) / left if left > 0 else float("inf")
            counted = left >= 0.05 * loop
            if counted:
                worst = max(worst, abs(error))
            print("  %8.1f %10.3g %10.3g %+7.1f%%%s" % (wall - start, eta, left, 100 * error,
                                                      "" if counted else "  (last 5 %)"))
        print("  worst over the last half: %.1f %%" % (100 * worst))
    return status


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1:]))
