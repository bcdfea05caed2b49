#!/usr/bin/python3
"""Whether two run.h5 files hold the same run: every group, dataset (shape, type and every bit of
its values) and attribute equal, but for the checkpoint and rebalance keys of the root attribute
`scene` (the composed scene), which say only when checkpoints are written and how the element work
is shared by MPI ranks.

    /usr/bin/python3 same_run.py A B     exit 0: the same run; 1: not (what differs on stdout)
"""
import sys

import h5py
import numpy as np

IGNORED_KEYS = ("checkpoint_interval = ", "checkpoint_time = ", "rebalance_imbalance = ",
                "rebalance_every = ")


def scene_without_ignored_keys(text):
    return "\n".join(line for line in text.split("\n") if not line.startswith(IGNORED_KEYS))


def items(path):
    """Every object's attributes and every dataset's bytes, by name."""
    out = {}
    with h5py.File(path, "r") as f:
        def add(name, obj):
            for key, value in obj.attrs.items():
                if name == "/" and key == "scene":
                    value = scene_without_ignored_keys(value)
                out["%s@%s" % (name, key)] = repr(value)
            if isinstance(obj, h5py.Dataset):
                data = obj[()]
                out[name] = (data.dtype.str, data.shape, np.ascontiguousarray(data).tobytes())
            elif name != "/":
                out[name] = "group"
        add("/", f)
        f.visititems(add)
    return out


def main(a, b):
    x, y = items(a), items(b)
    differ = sorted(k for k in set(x) | set(y) if x.get(k) != y.get(k))
    for k in differ[:20]:
        print("differs: %s" % k)
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
