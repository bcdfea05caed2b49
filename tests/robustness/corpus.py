"""CTest robustness_corpus (label robustness): a corpus of bad inputs and faults, tried as a new
user would try them, on every command of `mesopen`. Each case must end with the exit code the README
promises (2 for bad input, 1 for a failure during a run, 0 where the input is accepted, 130 or 143
when stopped by SIGINT or SIGTERM) and with a first message line that names the problem (a short
expected text: the key, the file, the option); never by a signal, never by a hang.

Categories:
  - cli: missing, repeated, unknown and malformed commands, arguments and options (--seed,
    --threads, --modes, --replicates, -o '');
  - file: missing scene, a directory, a FIFO or /dev/null as scene, empty and binary files, a BOM,
    CRLF line ends, nesting 100,000 deep;
  - syntax: bad TOML (unclosed headers and strings, keys given twice, numbers beyond a double or
    64 bits), tables where keys belong and keys where tables belong;
  - keys: unknown tables and keys, and for every key of the scene table (docs/scene-keys.md, as
    `mesopen keys` prints it) and every material parameter: a value just below and just above its
    range, and a value of the wrong type (these cases are generated from that table);
  - numbers: NaN, inf, -0.0, 1e308, denormals, integers too large, a value 100,000 characters long;
  - together: scenes whose keys are each in range but not together (too many triangles, a
    projectile that cannot be drawn, a clamped projectile, ...);
  - materials: bad presets, types and parameters;
  - accepted: in-range extremes that must run (exit 0, status completed, every number finite);
  - failure: runs that fail (exit 1) and say where;
  - output: output directories that cannot be made or written, that hold another command's or
    stale files, that another run is writing;
  - analyze, modal, campaign: bad directories, damaged or foreign HDF5 files, bad campaign files,
    a campaign with a failing run or a run `mesopen run` refuses, a second campaign on a
    directory in use;
  - dem: a few tiny runs with the grains as LIGGGHTS disks and their specific checks;
  - signal: SIGTERM or SIGINT sent to a running `mesopen run` (fe, dem, hybrid) or campaign, in
    the time loop: exit 143 or 130 and summary.json with status "interrupted".

After every case, every file the case left behind (new or changed) must open whole: *.h5 with
h5py (every dataset read), *.json with json, *.toml with tomllib, *.csv with csv (every row as
long as the header), *.pvd and *.vtu/*.vtp/*.vtk as XML (raw appended data checked block by
block against its declared sizes), *.png to its IEND chunk; and no *.tmp may be left after an exit
other than by a signal (after an interrupted run, a *.tmp is allowed beside a final file that is
whole, or absent). Cases run on tiny scenes (0.6 x 0.3 mm, 60 um grains), two at a time.

    corpus.py MESOPEN SCRATCH_DIR
"""
import csv
import json
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import tomllib
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor

import h5py
import numpy as np

LIMIT = 60          # seconds a case may take before it counts as a hang
WORKERS = 2

# The tiny scene every case starts from: about 45 grains and 1,600 triangles, 70 steps.
BASE = {
    "target": {"width": "0.6e-3", "height": "0.3e-3", "diameter": "60e-6", "mesh_size": "15e-6"},
    "projectile": {"length": "0.3e-3"},
    "run": {"end_time": "2e-8", "frame_interval": "1e-8"},
}

# The same running long enough (1e-5 s, thousands of steps) to be signalled in its time loop.
LONG = {"run.end_time": "1e-5", "run.frame_interval": "1e-7"}

# A run that fails within a few steps: 10 km/s into elastic grains, no viscosity, no erosion.
FAILING = {"run.velocity": "10000.0", "run.safety": "1.0", "run.viscosity_linear": "0.0",
           "run.viscosity_quadratic": "0.0", "run.erode_step_ratio": "0.0",
           "contact.stiffness": "0.6", "contact.damping": "0.0",
           "materials.grains.preset": '"quartz-elastic"'}

# A small beam for `mesopen modal` (1,300 nodes).
BEAM = {"modal.body": '"beam"', "modal.length": "0.01", "modal.height": "0.001", "modal.modes": "3"}

# What each command is given beside its input and output, so that cases stay quick and quiet.
QUIET = {"run": ["--threads", "1", "--quiet"], "target": ["--threads", "1", "--no-plot"],
         "modal": ["--threads", "1"], "campaign": ["--threads", "1", "--quiet"]}


def scene(changes=None):
    """TOML text of BASE with `changes`: {"table.key": TOML value text, or None to remove the
    key}; the table may be dotted ("materials.grains.preset")."""
    tables = {t: dict(kv) for t, kv in BASE.items()}
    for dotted, value in (changes or {}).items():
        table, key = dotted.rsplit(".", 1)
        tables.setdefault(table, {})
        if value is None:
            tables[table].pop(key, None)
        else:
            tables[table][key] = value
    return "".join("[%s]\n%s" % (t, "".join("%s = %s\n" % kv for kv in keys.items()))
                   for t, keys in tables.items() if keys)


class Case:
    """One command and what it must do.

    args: the words after `mesopen`, run in the case's own directory; files: what is made there
    first ({name: text, bytes, or a function of the case directory}; a name ending in "/" is a
    directory); code: the exit code wanted; text: a short text the first line of the message must
    hold (stderr's after an exit other than 0, stdout's after 0, either when the other is empty;
    line="any": any line of either);
    warn: a text stderr must hold; checks: functions of the case directory returning problems;
    signals: (file to wait for, signal to send then); during: the words of a command
    started first and kept running (until SIGTERM) while this one runs, and the file to wait for.
    """

    def __init__(self, category, name, args, code, text, files=None, line="first", warn=None,
                 checks=(), signals=None, during=None):
        self.category, self.name, self.args, self.code, self.text = category, name, args, code, text
        self.files, self.line, self.warn = files or {}, line, warn
        self.checks, self.signals, self.during = list(checks), signals, during


# ---- what a file left behind must be -----------------------------------------------------------

def check_h5(path):
    with h5py.File(path, "r") as h5:
        def read(name, obj):
            for key in obj.attrs:
                obj.attrs[key]
            if isinstance(obj, h5py.Dataset):
                obj[()]
        read("/", h5)
        h5.visititems(read)


def check_vtk_xml(path):
    """An XML VTK file; raw appended data (not XML) is cut out and checked against the sizes its
    blocks declare: each array's block ends within the data, and the last one where it ends."""
    with open(path, "rb") as f:
        data = f.read()
    start = data.find(b"<AppendedData")
    if start < 0:
        ET.fromstring(data)
        return
    close = data.rfind(b"</AppendedData>")
    mark = data.find(b"_", data.find(b">", start)) + 1
    if close < 0 or mark <= 0 or close < mark:
        raise ValueError("appended data without its end")
    root = ET.fromstring(data[:start] + b"<AppendedData/>" + data[close + len(b"</AppendedData>"):])
    if root.get("compressor"):
        return
    size_format = "<Q" if root.get("header_type", "UInt32") == "UInt64" else "<I"
    header = struct.calcsize(size_format)
    raw = data[mark:close]
    end = 0
    for array in root.iter("DataArray"):
        if array.get("format") != "appended":
            continue
        offset = int(array.get("offset"))
        if offset + header > len(raw):
            raise ValueError("array %s starts past the data" % array.get("Name"))
        (size,) = struct.unpack_from(size_format, raw, offset)
        if offset + header + size > len(raw):
            raise ValueError("array %s ends past the data" % array.get("Name"))
        end = max(end, offset + header + size)
    if raw[end:].strip():
        raise ValueError("%d bytes after the last array" % len(raw[end:].strip()))


def check_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if not data.startswith(b"\x89PNG\r\n\x1a\n") or not data.endswith(b"IEND\xaeB`\x82"):
        raise ValueError("not a whole PNG")


def check_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or any(len(r) != len(rows[0]) for r in rows):
        raise ValueError("rows of unequal length")


def check_json(path):
    with open(path) as f:
        json.load(f)


def check_toml(path):
    with open(path, "rb") as f:
        tomllib.load(f)


CHECKS = {".h5": check_h5, ".json": check_json, ".toml": check_toml, ".csv": check_csv,
          ".pvd": check_vtk_xml, ".vtu": check_vtk_xml, ".vtp": check_vtk_xml,
          ".vtk": check_vtk_xml, ".png": check_png}


def snapshot(d):
    """Every file under d with its size and modification time."""
    seen = {}
    for root, _, names in os.walk(d):
        for n in names:
            p = os.path.join(root, n)
            try:
                st = os.lstat(p)
            except OSError:
                continue
            seen[p] = (st.st_size, st.st_mtime_ns)
    return seen


def files_left(d, before, code):
    """Problems with the files the case made or changed under d."""
    problems = []
    for p, stamp in sorted(snapshot(d).items()):
        if before.get(p) == stamp or os.path.islink(p):
            continue
        rel = os.path.relpath(p, d)
        if p.endswith(".tmp"):
            # after an interrupt, allowed: its final file, when there, is checked whole here
            if code not in (130, 143):
                problems.append("left %s after exit %s" % (rel, code))
            continue
        check = CHECKS.get(os.path.splitext(p)[1])
        if check:
            try:
                check(p)
            except Exception as e:
                problems.append("%s does not open whole: %s" % (rel, str(e)[:200]))
    return problems


# ---- checks of a case's results ----------------------------------------------------------------

def summary_holds(rel, key, want):
    """summary.json at rel holds `key` = `want`."""
    def check(d):
        try:
            with open(os.path.join(d, rel)) as f:
                got = json.load(f).get(key)
        except (OSError, ValueError) as e:
            return ["%s: %s" % (rel, e)]
        return [] if got == want else ["%s: %s %r, want %r" % (rel, key, got, want)]
    return check


def status(rel, want):
    """summary.json at rel holds status `want`."""
    return summary_holds(rel, "status", want)


def completed(out="out"):
    """A completed run: status completed, every energy given, every number of run.h5 finite."""
    def check(d):
        problems = status(os.path.join(out, "summary.json"), "completed")(d)
        if problems:
            return problems
        with open(os.path.join(d, out, "summary.json")) as f:
            energy = json.load(f).get("energy", {})
        problems += ["summary.json: energy.%s is null" % k for k, v in energy.items() if v is None]
        bad = []

        def finite(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f":
                if not np.all(np.isfinite(obj[()])):
                    bad.append(name)
        with h5py.File(os.path.join(d, out, "run.h5"), "r") as h5:
            h5.visititems(finite)
        if bad:
            problems.append("run.h5: not finite: %s" % ", ".join(bad[:5]))
        return problems
    return check


def exists(rel, present=True):
    def check(d):
        there = os.path.lexists(os.path.join(d, rel))
        if there == present:
            return []
        return ["%s %s" % (rel, "missing" if present else "left behind")]
    return check


def campaign_interrupted(d):
    try:
        with open(os.path.join(d, "out", "summary.json")) as f:
            interrupted = json.load(f).get("interrupted")
    except (OSError, ValueError) as e:
        return ["out/summary.json: %s" % e]
    return [] if interrupted is True else ["out/summary.json: interrupted = %r" % interrupted]


# ---- file makers -------------------------------------------------------------------------------

def copy_of(source):
    def make(path):
        (shutil.copytree if os.path.isdir(source) else shutil.copyfile)(source, path)
    return make


def truncated(source, size):
    def make(path):
        with open(source, "rb") as f, open(path, "wb") as g:
            g.write(f.read(size))
    return make


def h5_with(datasets):
    """An HDF5 file holding {name: array}."""
    def make(path):
        with h5py.File(path, "w") as h5:
            for name, value in datasets.items():
                h5[name] = value
    return make


def fifo(path):
    os.mkfifo(path)


# ---- the corpus --------------------------------------------------------------------------------

def key_table(mesopen):
    """Rows of `mesopen keys` (the table of docs/scene-keys.md): (section, name, type, allowed) for
    every scene key and material parameter; section None for scene keys, else the material
    type."""
    text = subprocess.run([mesopen, "keys"], capture_output=True, text=True, check=True).stdout
    rows, section = [], None
    for line in text.splitlines():
        m = re.match(r'### type "(.*)"', line)
        if m:
            section = m.group(1)
            continue
        if not line.startswith("|") or line.startswith("|---"):
            continue
        cols = [c.strip() for c in line.strip().strip("|").split("|")]
        if cols[0] in ("key", "parameter", "preset") or len(cols) < 6:
            continue
        if section is None and "." not in cols[0]:
            continue  # the presets' table
        rows.append((section, cols[0], cols[1], cols[3]))
    return rows


def toml_number(value, integer):
    return str(int(value)) if integer else repr(float(value))


# Which command reads a scene table in the generated cases (each command reads the whole scene;
# spreading the tables over them tries every command's reading).
TABLE_COMMAND = {"target": "target", "projectile": "target", "run": "run", "contact": "run",
                 "dem": "run", "modal": "modal"}
# Which material table holds each material type in the generated cases.
TYPE_GROUP = {"elastic": "grains", "quartz": "grains", "von-mises": "projectile"}


def generated_cases(mesopen):
    """For every key and material parameter: below and above its range, and a wrong type."""
    cases = []
    for section, name, kind, allowed in key_table(mesopen):
        if section is None:
            command = TABLE_COMMAND[name.split(".", 1)[0]]
            full, extra = name, {}
        else:
            group = TYPE_GROUP[section]
            command = "run"
            full = "materials.%s.%s" % (group, name)
            extra = {"materials.%s.type" % group: '"%s"' % section}
            name = "%s.%s" % (section, name)

        def add(label, value, text):
            changes = dict(extra)
            changes[full] = value
            cases.append(Case("keys", "%s %s = %s" % (label, name, value[:24]),
                              [command, "scene.toml", "-o", "out"] + QUIET[command], 2, text,
                              files={"scene.toml": scene(changes)}))

        rng = re.match(r"^(\S+) (<=|<) (\w+) (<=|<) (\S+)$", allowed)
        integer = kind == "integer"
        if rng:
            lo, lo_op, hi = float(rng.group(1)), rng.group(2), float(rng.group(5))
            # just outside: the open bound itself, half a positive bound, a little below 0
            span = max(abs(lo), abs(hi))
            if integer:
                below, above = lo - 1, hi + 1
            else:
                below = lo if lo_op == "<" else lo / 2 if lo > 0 else lo - span * 1e-3
                above = hi + span * 1e-3
            add("below", toml_number(below, integer), full + " = ")
            add("above", toml_number(above, integer), full + " = ")
            if integer:
                add("type", "1.5", "is not an integer")
            else:
                add("type", '"big"', "is not a number")
        elif allowed == "true or false":
            add("type", '"yes"', "is not true or false")
        elif allowed.startswith("one of"):
            add("unknown", '"nonsense"', "is not known")
            add("type", "1", "is not a string")
    return cases


def corpus(mesopen, ref):
    """The hand-written cases. `ref`: directories of a finished tiny run, target, failed run."""
    cases = []
    S = {"scene.toml": scene()}

    def add(category, name, args, code, text, **kw):
        cases.append(Case(category, name, args, code, text, **kw))

    def cmd(command, *extra):
        return [command, "scene.toml", "-o", "out"] + QUIET[command] + list(extra)

    def bad_scene(category, name, changes, text, command="run", code=2, **kw):
        add(category, name, cmd(command), code, text,
            files={"scene.toml": scene(changes) if isinstance(changes, dict) else changes}, **kw)

    def good_run(category, name, changes, **kw):
        checks = [completed()] + kw.pop("checks", [])
        files = kw.pop("files", {"scene.toml": scene(changes)})
        add(category, name, cmd("run"), 0, "steps to t =", files=files, checks=checks, **kw)

    # -- cli ----------------------------------------------------------------------------------
    add("cli", "no arguments", [], 2, "subcommand is required")
    add("cli", "--help", ["--help"], 0, "mesopen")
    add("cli", "run --help", ["run", "--help"], 0, "run a scene")
    add("cli", "keys", ["keys"], 0, "| key |")
    add("cli", "keys with an argument", ["keys", "extra"], 2, "extra")
    add("cli", "run without a scene", ["run", "-o", "out"], 2, "scene is required")
    add("cli", "run without -o", ["run", "scene.toml"], 2, "--output is required", files=S)
    for command in ("run", "target", "modal", "campaign"):
        add("cli", "%s -o ''" % command, [command, "scene.toml", "-o", ""], 2,
            "--output: an empty name", files=S)
    add("cli", "analyze -o ''", ["analyze", "run", "-o", ""], 2, "--output: an empty name",
        files={"run/": copy_of(ref["run"])})
    add("cli", "unknown option", cmd("run", "--bogus"), 2, "--bogus", files=S)
    add("cli", "run-only flag on target", cmd("target", "--quiet"), 2, "--quiet", files=S)
    for value in ("-1", "abc", "1e3", "99999999999999999999", "", "9000000000000001", "0x10"):
        add("cli", "--seed %r" % value, cmd("run", "--seed", value), 2, "--seed", files=S)
    add("cli", "--seed without a value", cmd("run", "--seed"), 2, "--seed", files=S)
    add("cli", "--seed twice", cmd("run", "--seed", "1", "--seed", "2"), 2, "--seed", files=S)
    add("cli", "--seed 9e15 (largest)", cmd("run", "--seed", "9000000000000000"), 0,
        "steps to t =", files=S, checks=[completed()])
    for value in ("0", "1025", "two", "-3", "1.5"):
        add("cli", "--threads %r" % value, ["run", "scene.toml", "-o", "out", "--threads", value],
            2, "--threads", files=S)
    add("cli", "--threads 1024 on a tiny run", ["run", "scene.toml", "-o", "out", "--threads",
                                                "1024", "--quiet"], 0, "steps to t =", files=S,
        checks=[completed()])
    add("cli", "-o twice", cmd("run", "-o", "other"), 2, "--output", files=S)
    add("cli", "two scenes", ["run", "scene.toml", "scene.toml", "-o", "out"], 2, "scene.toml",
        files=S)
    for value in ("0", "201", "x"):
        add("cli", "modal --modes %r" % value, cmd("modal", "--modes", value), 2, "--modes",
            files=S)
    for value in ("0", "1001"):
        add("cli", "campaign --replicates %s" % value,
            ["campaign", "c.toml", "-o", "out", "--replicates", value], 2, "--replicates",
            files={"c.toml": '[campaign]\nbase = "scene.toml"\n[[run]]\nname = "a"\n', **S})
    add("cli", "analyze without directories", ["analyze"], 2, "dirs is required")
    add("cli", "misspelt command rnu", ["rnu", "scene.toml", "-o", "out"], 2,
        "unknown command 'rnu'; allowed: target, run, analyze, modal, campaign, keys", files=S)
    add("cli", "misspelt option --versoin", ["--versoin"], 2,
        "unknown option '--versoin'; allowed: --help, --version")

    # -- file ---------------------------------------------------------------------------------
    for command in ("run", "target", "modal", "campaign"):
        add("file", "%s: no such scene" % command, [command, "nothere.toml", "-o", "out"], 2,
            "nothere.toml: no such file")
    for command in ("run", "target", "modal", "campaign"):
        add("file", "%s: a directory as scene" % command, [command, "adir", "-o", "out"], 2,
            "adir: not a file", files={"adir/": None})
    add("file", "a FIFO as scene", ["run", "pipe.toml", "-o", "out"], 2, "pipe.toml: not a file",
        files={"pipe.toml": fifo})
    add("file", "/dev/null as scene", ["run", "/dev/null", "-o", "out"], 2, "/dev/null: not a file")
    add("file", "empty scene: modal (the default projectile)", cmd("modal"), 0, "modes in",
        files={"scene.toml": ""})
    add("file", "empty scene: target --no-mesh (the default target)", cmd("target", "--no-mesh"),
        0, "grains", files={"scene.toml": ""})
    add("file", "comments only: modal", cmd("modal"), 0, "modes in",
        files={"scene.toml": "# nothing\n\n   # here\n"})
    add("file", "empty campaign", ["campaign", "c.toml", "-o", "out"], 2, "no [[run]]",
        files={"c.toml": ""})
    bad_scene("file", "random bytes", bytes(np.random.default_rng(1).integers(0, 256, 3000,
                                                                            dtype=np.uint8)),
              "not valid TOML")
    bad_scene("file", "a NUL byte", b"[run]\x00\n", "not valid TOML")
    bad_scene("file", "latin-1 in a comment", b"# caf\xe9\n" + scene().encode(), "not valid TOML")
    bad_scene("file", "run.h5 given as scene", copy_of(os.path.join(ref["run"], "run.h5")),
              "not valid TOML")
    add("file", "UTF-8 BOM", cmd("run"), 0, "steps to t =",
        files={"scene.toml": b"\xef\xbb\xbf" + scene().encode()}, checks=[completed()])
    add("file", "CRLF line ends", cmd("run"), 0, "steps to t =",
        files={"scene.toml": scene().replace("\n", "\r\n")}, checks=[completed()])
    add("file", "a scene named .txt: modal", ["modal", "scene.txt", "-o", "out", "--threads", "1"],
        0, "modes in", files={"scene.txt": scene(BEAM)})
    bad_scene("file", "arrays nested 100,000 deep", "x = " + "[" * 100000 + "]" * 100000 + "\n",
              "nested")
    bad_scene("file", "inline tables nested 20,000 deep", "x = " + "{a=" * 20000 + "1" +
              "}" * 20000 + "\n", "nested")

    # -- TOML syntax ---------------------------------------------------------------------------
    bad_scene("syntax", "unclosed table header", "[target\nwidth = 1e-3\n", "scene.toml:1:")
    bad_scene("syntax", "key without a value", "[target]\nwidth =\n", "scene.toml:2:")
    bad_scene("syntax", "bare word as value", "[target]\nwidth = big\n", "scene.toml:2:")
    bad_scene("syntax", "unterminated string", '[target]\nplacement = "regular\n', "scene.toml:2:")
    bad_scene("syntax", "unterminated inline table",
              "[materials]\ngrains = { preset = \"quartz\"\n", "scene.toml:2:")
    bad_scene("syntax", "key given twice", scene() + "end_time = 3e-8\n", "end_time")
    bad_scene("syntax", "table given twice", scene() + "[run]\n", "'run'")
    bad_scene("syntax", "number beyond double (1e400)", scene({"target.width": "1e400"}), "1e400")
    bad_scene("syntax", "integer beyond 64 bits", scene({"target.seed": "99999999999999999999"}),
              "scene.toml:6:")
    bad_scene("syntax", "key outside any table", "width = 1e-3\n" + scene(), "width")
    bad_scene("syntax", "[[target]] (array of tables)", "[[target]]\nwidth = 1e-3\n",
              "target must be a table")
    bad_scene("syntax", "target = 5", "target = 5\n", "target must be a table")
    bad_scene("syntax", "materials = 5", "materials = 5\n", "materials must be a table")
    bad_scene("syntax", "[target.sub] table", scene() + "[target.sub]\nx = 1\n", "target.sub")

    # -- unknown tables and keys ----------------------------------------------------------------
    bad_scene("keys", "unknown table [foo]", scene() + "[foo]\nx = 1\n", "[foo]")
    bad_scene("keys", "table in capitals [Target]", "[Target]\nwidth = 1e-3\n", "[Target]")
    bad_scene("keys", "misspelt target.widht", scene({"target.widht": "1e-3"}), "target.widht")
    bad_scene("keys", "misspelt run.end_tme", scene({"run.end_tme": "1e-8"}), "run.end_tme")
    bad_scene("keys", "misspelt projectile.lenght", scene({"projectile.lenght": "1e-3"}),
              "projectile.lenght")
    bad_scene("keys", "misspelt contact.frction", scene({"contact.frction": "0.1"}),
              "contact.frction")
    bad_scene("keys", "unknown dem.bogus", scene({"dem.bogus": "3"}), "dem.bogus")
    bad_scene("keys", "misspelt modal.mode", scene({"modal.mode": "3"}), "modal.mode",
              command="modal")
    bad_scene("keys", "unknown [materials.sand]", scene({"materials.sand.preset": '"quartz"'}),
              "materials.sand")

    # -- special numbers ------------------------------------------------------------------------
    for key, value in (("target.width", "nan"), ("target.height", "-nan"), ("run.end_time", "inf"),
                       ("run.velocity", "-inf"), ("contact.friction", "nan"),
                       ("run.spin", "inf"), ("target.porosity", "-0.0"),
                       ("target.width", "-0.0"), ("run.end_time", "-1e-8"),
                       ("target.mesh_size", "1e308"), ("target.width", "9223372036854775807"),
                       ("run.max_steps", "-9223372036854775808"), ("run.max_steps", "1e3"),
                       ("target.seed", "1.5"), ("run.series_interval", "0"),
                       ("dem.stiffness", "inf"), ("materials.grains.density", "nan"),
                       ("materials.projectile.yield_stress", "inf"),
                       ("materials.grains.relaxation_time", "0.0")):
        command = "modal" if key.startswith("modal") else "run"
        bad_scene("numbers", "%s = %s" % (key, value), scene({key: value}), key + " = ",
                  command=command)
    bad_scene("numbers", "modal.length = nan",
              scene({"modal.body": '"beam"', "modal.length": "nan"}), "modal.length = ",
              command="modal")
    bad_scene("numbers", "target.diameter = [nan, 6e-5]", scene({"target.diameter": "[nan, 6e-5]"}),
              "target.diameter")
    bad_scene("numbers", "target.diameter = [8e-5, 4e-5] (min > max)",
              scene({"target.diameter": "[8e-5, 4e-5]"}), "min > max")
    bad_scene("numbers", "target.diameter = [6e-5] (one value)",
              scene({"target.diameter": "[6e-5]"}), "target.diameter")
    bad_scene("numbers", "target.diameter = [] (none)", scene({"target.diameter": "[]"}),
              "target.diameter")
    bad_scene("numbers", "target.diameter = [4e-5, 6e-5, 8e-5]",
              scene({"target.diameter": "[4e-5, 6e-5, 8e-5]"}), "target.diameter")
    bad_scene("numbers", "target.diameter = [4e-5, \"a\"]",
              scene({"target.diameter": '[4e-5, "a"]'}), "target.diameter")
    bad_scene("numbers", "a string of 100,000 characters",
              scene({"target.placement": '"%s"' % ("x" * 100000)}), "characters) is not known")
    good_run("numbers", "run.end_time = 5e-324 (a denormal: one step)", {"run.end_time": "5e-324"})

    # -- keys in range, not together ------------------------------------------------------------
    T = "together"
    bad_scene(T, "box narrower than 4 grains", scene({"target.width": "0.2e-3"}),
              "at least 4 grain diameters", command="target")
    bad_scene(T, "mesh_size over half a grain", scene({"target.mesh_size": "40e-6"}),
              "target.mesh_size", command="target")
    bad_scene(T, "mesh of 1e-8 m: too many triangles", scene({"target.mesh_size": "1e-8"}),
              "target.mesh_size", command="target")
    bad_scene(T, "10 x 10 m of 1 um grains: too many sites",
              scene({"target.width": "10.0", "target.height": "10.0", "target.diameter": "1e-6",
                     "target.mesh_size": "4e-7"}), "sites", command="target")
    bad_scene(T, "projectile 1 m long at 15 um", scene({"projectile.length": "1.0"}),
              "projectile.length", command="target")
    bad_scene(T, "crh 0.5 with tip facets", scene({"projectile.crh": "0.5"}), "[projectile]",
              command="target")
    bad_scene(T, "l/d 1: nose longer than the projectile",
              scene({"projectile.length_over_diameter": "1.0"}), "[projectile]", command="target")
    bad_scene(T, "tip half-angle 1 deg", scene({"projectile.tip_half_angle": "1.0"}),
              "tip_half_angle", command="target")
    bad_scene(T, "spin with constant velocity",
              scene({"run.constant_velocity": "true", "run.spin": "1.0"}), "run.spin")
    bad_scene(T, "run with target.mesh = none", scene({"target.mesh": '"none"'}), "target.mesh")
    bad_scene(T, "run without the projectile", scene({"projectile.enabled": "false"}),
              "projectile.enabled")
    bad_scene(T, "modal: a clamped projectile", scene({"modal.support": '"clamped"'}),
              "modal.support", command="modal")
    bad_scene(T, "modal: beam mesh larger than the beam",
              scene(dict(BEAM, **{"modal.mesh_size": "0.05"})), "modal.mesh_size",
              command="modal")
    bad_scene(T, "modal: beam of too many triangles",
              scene(dict(BEAM, **{"modal.length": "1000.0", "modal.height": "1000.0",
                                  "modal.mesh_size": "0.01"})), "modal.mesh_size",
              command="modal")
    bad_scene(T, "modal: projectile disabled", scene({"projectile.enabled": "false"}),
              "projectile.enabled", command="modal")
    bad_scene(T, "modal: more modes than unknowns", scene({"modal.mesh_size": "50.0"}),
              "modes asked", command="modal")
    bad_scene(T, "modal: 200 modes of a 3-element beam",
              scene(dict(BEAM, **{"modal.mesh_size": "0.001", "modal.modes": "200"})),
              "modes asked", command="modal")

    # -- materials ------------------------------------------------------------------------------
    M = "materials"
    bad_scene(M, "unknown preset", scene({"materials.grains.preset": '"granite"'}),
              "materials.grains.preset")
    bad_scene(M, "unknown type", scene({"materials.grains.type": '"rubber"'}),
              "materials.grains.type")
    bad_scene(M, "preset and type", scene({"materials.grains.preset": '"quartz"',
                                           "materials.grains.type": '"quartz"'}),
              "preset or type, not both")
    bad_scene(M, "preset = 5", scene({"materials.projectile.preset": "5"}),
              "materials.projectile.preset")
    bad_scene(M, "yield_stress on quartz", scene({"materials.grains.yield_stress": "1e9"}),
              "materials.grains.yield_stress")
    bad_scene(M, "strength on elastic", scene({"materials.grains.type": '"elastic"',
                                               "materials.grains.strength": "false"}),
              "materials.grains.strength")
    bad_scene(M, "plastic = 1", scene({"materials.projectile.plastic": "1"}),
              "materials.projectile.plastic")
    bad_scene(M, "density = \"heavy\"", scene({"materials.projectile.density": '"heavy"'}),
              "materials.projectile.density")
    good_run(M, "quartz-elastic grains, steel-elastic projectile",
             {"materials.grains.preset": '"quartz-elastic"',
              "materials.projectile.preset": '"steel-elastic"'})
    good_run(M, "steel-elastic with plastic = true", {"materials.projectile.preset":
                                                      '"steel-elastic"',
                                                      "materials.projectile.plastic": "true"})
    good_run(M, "elastic grains of shear modulus 0", {"materials.grains.type": '"elastic"',
                                                      "materials.grains.shear_modulus": "0.0"})
    good_run(M, "quartz grains of density 1", {"materials.grains.density": "1.0"})
    good_run(M, "projectile of yield stress 0", {"materials.projectile.yield_stress": "0.0"})

    # -- accepted: in-range extremes ------------------------------------------------------------
    A = "accepted"
    good_run(A, "max_steps = 1", {"run.max_steps": "1"})
    good_run(A, "series_interval = 1e9", {"run.series_interval": "1000000000"})
    good_run(A, "frame_interval = 0 (no frames)", {"run.frame_interval": "0.0"},
             checks=[exists("out/vtk/run.pvd", False)])
    good_run(A, "frame_interval = 1 (start and end)", {"run.frame_interval": "1.0"})
    good_run(A, "end_depth = 1e-9 lengths", {"run.end_depth": "1e-9"})
    good_run(A, "velocity = 0", {"run.velocity": "0.0"})
    good_run(A, "safety = 0.001", {"run.safety": "0.001", "run.end_time": "2e-9"})
    good_run(A, "no grains", {"run.grains": "false"})
    good_run(A, "no contact", {"contact.enabled": "false"})
    good_run(A, "vtk = false", {"run.vtk": "false"}, checks=[exists("out/vtk/run.pvd", False)])
    good_run(A, "every switch the other way",
             {"run.fix_edges": "false", "run.smooth_walls": "true", "run.constant_velocity":
              "true", "run.anti_locking": "true", "run.mass_scaling_step_ratio": "1.0",
              "run.erode_step_ratio": "1.0"})
    good_run(A, "plate projectile", {"projectile.shape": '"plate"', "projectile.length": "60e-6"})
    good_run(A, "contact stiffness 0.6, damping 2", {"contact.stiffness": "0.6",
                                                     "contact.damping": "2.0"})
    good_run(A, "tip_facet_length = 0 (sharp tip)", {"projectile.tip_facet_length": "0.0"})
    good_run(A, "projectile mesh_size = 1 m", {"projectile.mesh_size": "1.0"})
    good_run(A, "[dem] in an fe run (a warning)", {"dem.stiffness": "1e9"}, warn="[dem]")
    good_run(A, "band_half_width in an fe run (a warning)", {"run.band_half_width": "1e-3"},
             warn="run.band_half_width")
    for key, value, warn in (("target.porosity", "0.6", "porosity"),
                             ("target.porosity", "0.05", "porosity"),
                             ("target.placement", '"clustered"', None),
                             ("target.tessellation", '"voronoi"', None),
                             ("target.mesh", '"fan"', None),
                             ("target.mesh", '"none"', None),
                             ("target.void_scale", "5.0", "porosity"),
                             ("target.max_iterations", "100000", None),
                             ("target.seed", "9000000000000000", None)):
        add(A, "target: %s = %s" % (key, value), cmd("target"), 0, "grains",
            files={"scene.toml": scene({key: value})}, warn=warn)
    add(A, "target --no-mesh", cmd("target", "--no-mesh"), 0, "grains", files=S)
    add(A, "target with the histogram plot", ["target", "scene.toml", "-o", "out", "--threads",
                                              "1"], 0, "grains", files=S)
    add(A, "output path with spaces", ["run", "scene.toml", "-o", "o u t"] + QUIET["run"], 0,
        "steps to t =", files=S, checks=[completed("o u t")])
    add(A, "output path in UTF-8", ["run", "scene.toml", "-o", "r\u00e9sultat"] + QUIET["run"], 0,
        "steps to t =", files=S, checks=[completed("r\u00e9sultat")])
    add(A, "output path ending in /", ["run", "scene.toml", "-o", "out/"] + QUIET["run"], 0,
        "steps to t =", files=S, checks=[completed()])
    add(A, "output three directories deep", ["run", "scene.toml", "-o", "a/b/out"] + QUIET["run"],
        0, "steps to t =", files=S, checks=[completed("a/b/out")])

    # -- run failures ---------------------------------------------------------------------------
    add("failure", "inverted element at 10 km/s", cmd("run"), 1, "inverted",
        files={"scene.toml": scene(FAILING)}, checks=[status("out/summary.json", "failed")])
    add("failure", "spin -1e9 rad/s", cmd("run"), 1, "inverted",
        files={"scene.toml": scene({"run.spin": "-1e9"})},
        checks=[status("out/summary.json", "failed")])

    # -- output directories ---------------------------------------------------------------------
    O = "output"
    add(O, "-o names a file", cmd("run"), 2, "out: cannot create the output directory",
        files={"out": "a file\n", **S})
    add(O, "-o below a file", ["run", "scene.toml", "-o", "afile/out"], 2,
        "afile/out: cannot create the output directory", files={"afile": "x\n", **S})
    add(O, "-o where no directory can be made", ["run", "scene.toml", "-o", "/proc/self/out"],
        2, "/proc/self/out: cannot create", files=S)
    add(O, "run into an unwritable directory (frames)", ["run", "scene.toml", "-o", "/proc/self"]
        + QUIET["run"], 2, "vtk: cannot create", files=S)
    add(O, "run into an unwritable directory (no frames)",
        ["run", "scene.toml", "-o", "/proc/self"] + QUIET["run"], 1, "cannot write mesopen.log",
        files={"scene.toml": scene({"run.frame_interval": "0.0"})})
    add(O, "target into an unwritable directory", ["target", "scene.toml", "-o", "/proc/self"]
        + QUIET["target"], 1, "cannot create", files=S)
    add(O, "modal into an unwritable directory", ["modal", "scene.toml", "-o", "/proc/self"]
        + QUIET["modal"], 1, "cannot create", files={"scene.toml": scene(BEAM)})
    add(O, "analyze -o an unwritable directory", ["analyze", "run", "-o", "/proc/self",
                                                  "--no-plot"], 1, "cannot create",
        files={"run/": copy_of(ref["run"])})
    add(O, "campaign into an unwritable directory",
        ["campaign", "c.toml", "-o", "/proc/self"] + QUIET["campaign"], 1, "cannot create",
        files={"c.toml": '[campaign]\nbase = "scene.toml"\n[[run]]\nname = "a"\n', **S})
    if os.geteuid() != 0:  # permissions do not hold for root
        add(O, "run into a read-only directory", ["run", "scene.toml", "-o", "ro"] + QUIET["run"],
            1, "ro", files={"ro/": lambda p: (os.makedirs(p), os.chmod(p, 0o555)), **S})
    add(O, "run into a target's directory", cmd("run"), 2, "holds the output of `mesopen target`",
        files={"out/": copy_of(ref["target"]), **S})
    add(O, "target into a run's directory", cmd("target"), 2, "holds the output of `mesopen run`",
        files={"out/": copy_of(ref["run"]), **S})
    add(O, "modal into a run's directory", cmd("modal"), 2, "holds the output of `mesopen run`",
        files={"out/": copy_of(ref["run"]), "scene.toml": scene(BEAM)})
    add(O, "analyze -o a target's directory", ["analyze", "run", "-o", "out", "--no-plot"], 2,
        "out: holds the output of `mesopen target`",
        files={"run/": copy_of(ref["run"]), "out/": copy_of(ref["target"])},
        checks=[summary_holds("out/summary.json", "command", "target")])
    add(O, "analyze -o another run's directory (its summary kept)",
        ["analyze", "run", "-o", "other", "--no-plot"], 0, "run: depth",
        files={"run/": copy_of(ref["run"]), "other/": copy_of(ref["run"])},
        checks=[summary_holds("other/summary.json", "command", "run")])
    add(O, "a second run into a directory in use", cmd("run"), 1,
        "out is in use by another mesopen run", files={"long.toml": scene(LONG), **S},
        during=(["run", "long.toml", "-o", "out"] + QUIET["run"], "out/vtk/frame_000001.vtu"),
        checks=[status("out/summary.json", "interrupted"), exists("out/vtk/frame_000001.vtu")])
    good_run(O, "run over a summary.json that is not JSON", {},
             files={"out/summary.json": "{not json", "scene.toml": scene()})
    good_run(O, "run over a stale run.h5.tmp and a stale frame", {},
             files={"out/run.h5.tmp": "junk", "out/vtk/frame_000009.vtu": "junk",
                    "scene.toml": scene()},
             checks=[exists("out/vtk/frame_000009.vtu", False), exists("out/run.h5.tmp", False)])
    good_run(O, "run over its own earlier output", {},
             files={"out/": copy_of(ref["run"]), "scene.toml": scene()})
    add(O, "out/run.h5 is a directory", cmd("run"), 1, "run.h5",
        files={"out/run.h5/x/": None, **S}, checks=[status("out/summary.json", "failed")])
    add(O, "out/vtk is a file", cmd("run"), 2, "vtk", files={"out/vtk": "x\n", **S})
    add(O, "out/vtk/frame_000001.vtu is a directory", cmd("run"), 1, "frame_000001.vtu",
        files={"out/vtk/frame_000001.vtu/x/": None, **S},
        checks=[status("out/summary.json", "failed")])

    # -- analyze --------------------------------------------------------------------------------
    N = "analyze"
    run_h5 = os.path.join(ref["run"], "run.h5")
    add(N, "no such directory", ["analyze", "nothere", "--no-plot"], 2, "nothere/run.h5")
    add(N, "a directory without run.h5", ["analyze", "empty", "--no-plot"], 2, "empty/run.h5",
        files={"empty/": None})
    add(N, "run.h5 a directory", ["analyze", "r", "--no-plot"], 2, "r/run.h5: not a file",
        files={"r/run.h5/": None})
    add(N, "a target's directory", ["analyze", "tg", "--no-plot"], 2, "tg/run.h5",
        files={"tg/": copy_of(ref["target"])})
    add(N, "a file, not a directory", ["analyze", "scene.toml", "--no-plot"], 2, "scene.toml",
        files=S)
    add(N, "run.h5 truncated to 20 kB", ["analyze", "r", "--no-plot"], 2, "r/run.h5",
        files={"r/": None, "r/run.h5": truncated(run_h5, 20000)})
    add(N, "run.h5 truncated to half", ["analyze", "r", "--no-plot"], 2, "r/run.h5",
        files={"r/": None, "r/run.h5": truncated(run_h5, os.path.getsize(run_h5) // 2)})
    add(N, "run.h5 of text", ["analyze", "r", "--no-plot"], 2, "r/run.h5",
        files={"r/run.h5": "not HDF5\n"})
    add(N, "run.h5 empty", ["analyze", "r", "--no-plot"], 2, "r/run.h5", files={"r/run.h5": ""})
    add(N, "run.h5 an HDF5 file of nothing", ["analyze", "r", "--no-plot"], 2, "/series/time",
        files={"r/": None, "r/run.h5": h5_with({})})
    add(N, "target.h5 named run.h5", ["analyze", "r", "--no-plot"], 2, "r/run.h5",
        files={"r/": None, "r/run.h5": copy_of(os.path.join(ref["target"], "target.h5"))})
    add(N, "one good, one missing", ["analyze", "run", "nothere", "--no-plot"], 2,
        "nothere/run.h5", files={"run/": copy_of(ref["run"])})
    add(N, "-o a file", ["analyze", "run", "-o", "afile"], 2, "afile: cannot create",
        files={"run/": copy_of(ref["run"]), "afile": "x\n"})
    add(N, "a finished run, no plots", ["analyze", "run", "--no-plot"], 0, "run: depth",
        files={"run/": copy_of(ref["run"])})
    add(N, "the same run twice", ["analyze", "run", "run", "--no-plot"], 0, "run: depth",
        files={"run/": copy_of(ref["run"])})
    add(N, "a failed run", ["analyze", "run", "--no-plot"], 0, "run: depth",
        files={"run/": copy_of(ref["failed"])})
    add(N, "two runs with plots into a new directory", ["analyze", "run", "other", "-o", "plots"],
        0, "run: depth", files={"run/": copy_of(ref["run"]), "other/": copy_of(ref["run"])},
        checks=[exists("plots/summary.json")])

    # -- modal ----------------------------------------------------------------------------------
    D = "modal"
    add(D, "no such .h5", ["modal", "nothere.h5", "-o", "out"], 2, "nothere.h5: no such file")
    add(D, "a text file named .h5", ["modal", "m.h5", "-o", "out"], 2, "m.h5: cannot read",
        files={"m.h5": "hello\n"})
    add(D, "truncated run.h5", ["modal", "run.h5", "-o", "out"], 2, "run.h5: cannot read",
        files={"run.h5": truncated(run_h5, 5000)})
    add(D, "HDF5 file without a mesh", ["modal", "m.h5", "-o", "out"], 2, "holds neither",
        files={"m.h5": h5_with({"x": np.zeros(3)})})
    tri = {"projectile/x": np.array([0.0, 1e-3, 0.0]), "projectile/y": np.array([0.0, 0.0, 1e-3])}
    add(D, "triangle naming node 7 of 3", ["modal", "m.h5", "-o", "out"], 2, "node 7",
        files={"m.h5": h5_with(dict(tri, **{"projectile/tri": np.array([[0, 1, 7]], "i4")}))})
    add(D, "degenerate triangle", ["modal", "m.h5", "-o", "out"], 2, "triangle 0",
        files={"m.h5": h5_with({"projectile/x": np.zeros(3), "projectile/y": np.zeros(3),
                                "projectile/tri": np.array([[0, 1, 2]], "i4")})})
    add(D, "NaN node", ["modal", "m.h5", "-o", "out"], 2, "triangle 0",
        files={"m.h5": h5_with({"projectile/x": np.array([0.0, np.nan, 0.0]),
                                "projectile/y": np.array([0.0, 0.0, 1e-3]),
                                "projectile/tri": np.array([[0, 1, 2]], "i4")})})
    add(D, "empty mesh", ["modal", "m.h5", "-o", "out"], 2, "empty",
        files={"m.h5": h5_with({"projectile/x": np.zeros(0), "projectile/y": np.zeros(0),
                                "projectile/tri": np.zeros((0, 3), "i4")})})
    add(D, "run.h5 named .toml", ["modal", "m.toml", "-o", "out"], 2, "not valid TOML",
        files={"m.toml": copy_of(run_h5)})
    add(D, "a run's run.h5", ["modal", "run.h5", "-o", "out"], 0, "modes in",
        files={"run.h5": copy_of(run_h5)})
    add(D, "a target's target.h5", ["modal", "target.h5", "-o", "out"], 0, "modes in",
        files={"target.h5": copy_of(os.path.join(ref["target"], "target.h5"))})
    add(D, "a clamped beam in plane stress", cmd("modal"), 0, "modes in",
        files={"scene.toml": scene(dict(BEAM, **{"modal.support": '"clamped"',
                                                "modal.plane": '"stress"'}))})
    add(D, "quartz beam", cmd("modal"), 0, "modes in",
        files={"scene.toml": scene(dict(BEAM, **{"materials.projectile.preset": '"quartz"'}))})
    add(D, "--modes 1 over modal.modes", cmd("modal", "--modes", "1"), 0, "1 modes",
        files={"scene.toml": scene(BEAM)})

    # -- campaign -------------------------------------------------------------------------------
    C = "campaign"
    one = '[campaign]\nbase = "scene.toml"\n[[run]]\nname = "a"\n'
    frames = {"scene.toml": scene({"run.frame_interval": "0.0"})}

    def bad_campaign(name, text, want, *extra, **kw):
        add(C, name, ["campaign", "c.toml", "-o", "out"] + QUIET["campaign"] + list(extra), 2,
            want, files=kw.pop("files", dict(frames, **{"c.toml": text})), **kw)

    bad_campaign("--representation foo", one, "--representation foo", "--representation", "foo")
    bad_campaign("--only an unknown run", one, "--only zzz", "--only", "zzz")
    bad_campaign("--only ''", one, "--only", "--only", "")
    bad_campaign("a scene given as campaign", scene(), "[projectile]")
    bad_campaign("bad TOML", "[campaign\n", "c.toml:1:")
    bad_campaign("campaign = 3", "campaign = 3\n", "campaign must be a table")
    bad_campaign("unknown table [campaigns]", '[campaigns]\nbase = "scene.toml"\n', "[campaigns]")
    bad_campaign("unknown key campaign.colour", one.replace("[[run]]", "colour = 1\n[[run]]"),
                 "campaign.colour")
    bad_campaign("no [[run]]", '[campaign]\nbase = "scene.toml"\n', "no [[run]]")
    bad_campaign("no base, no scene", '[campaign]\n[[run]]\nname = "a"\n', 'run "a" has no scene')
    bad_campaign("base not found", one.replace("scene.toml", "nothere.toml"), "nothere.toml")
    bad_campaign("run name ../evil", one.replace('"a"', '"../evil"'), "../evil")
    bad_campaign("run name empty", one.replace('"a"', '""'), "name = ''")
    bad_campaign("run without name", one.replace('name = "a"', 'label = "x"'), "name = (none)")
    bad_campaign("two runs named a", one + '[[run]]\nname = "a"\n', 'two runs are named "a"')
    bad_campaign("run = 5", 'run = 5\n[campaign]\nbase = "scene.toml"\n', "no [[run]]")
    for key, value in (("replicates", "0"), ("replicates", "2.5"), ("replicates", "1001"),
                       ("seed_stride", "0"), ("frames", '"yes"'), ("representation", '"mixed"'),
                       ("name", "5")):
        bad_campaign("campaign.%s = %s" % (key, value),
                     one.replace("[[run]]", "%s = %s\n[[run]]" % (key, value)), "campaign.%s" % key)
    bad_campaign("campaign.base = 5", '[campaign]\nbase = 5\n[[run]]\nname = "a"\n',
                 "campaign.base")
    bad_campaign("a run's key out of range", one + "run.velocity = -5.0\n", "run.velocity")
    bad_campaign("a run's unknown table", one + "bogus.key = 1\n", "[bogus]")
    # what `mesopen run` refuses in a scene whose keys are each in range: refused before any run
    for key, value in (("target.mesh", '"none"'), ("projectile.enabled", "false")):
        bad_campaign("a run of %s = %s" % (key, value), one + "%s = %s\n" % (key, value),
                     'replicate 1 (scene scene.toml): %s = ' % key,
                     checks=[exists("out/runs", False)])
    bad_campaign("--representation dem on a scene without grains", one, "run.representation",
                 "--representation", "dem",
                 files={"scene.toml": scene({"run.grains": "false", "run.frame_interval": "0.0"}),
                        "c.toml": one},
                 checks=[exists("out/runs", False)])
    bad_campaign("a later replicate's seed out of range",
                 one.replace("[[run]]", "seed_stride = 1000000000\nreplicates = 2\n[[run]]") +
                 "target.seed = 8999999999999999\n", "replicate 2")
    bad_campaign("reference = 5", one + "reference = 5\n", "reference must be a table")
    bad_campaign("reference.speed", one + "reference = { speed = 1 }\n", "reference.speed")
    two = one + '[[run]]\nname = "b"\n'
    for name, trend, want in (
            ("trend on a missing run", 'runs = ["a", "zz"]\nexpect = "rises"', '"zz"'),
            ("trend of one run", 'runs = ["a"]\nexpect = "rises"', "at least 2"),
            ("trend naming a run twice", 'runs = ["a", "a"]\nexpect = "rises"', "twice"),
            ("trend expect maybe", 'runs = ["a", "b"]\nexpect = "maybe"', "expect = 'maybe'"),
            ("trend without expect", 'runs = ["a", "b"]', "expect = (none)"),
            ("trend measure speed", 'runs = ["a", "b"]\nexpect = "rises"\nmeasure = "speed"',
             'measure = "speed"'),
            ("similar without tolerance", 'runs = ["a", "b"]\nexpect = "similar"', "tolerance"),
            ("tolerance -1", 'runs = ["a", "b"]\nexpect = "similar"\ntolerance = -1',
             "tolerance = -1"),
            ("tolerance on rises", 'runs = ["a", "b"]\nexpect = "rises"\ntolerance = 0.5',
             "tolerance = 0.5"),
            ("x decreasing", 'runs = ["a", "b"]\nexpect = "rises"\nx = [2, 1]', "x must"),
            ("x of one number", 'runs = ["a", "b"]\nexpect = "rises"\nx = [1]', "x must"),
            ("x on differs", 'runs = ["a", "b"]\nexpect = "differs"\nx = [1, 2]', "x must"),
            ("runs holds 3", 'runs = ["a", 3]\nexpect = "rises"', "runs holds 3"),
            ("unknown trend key", 'runs = ["a", "b"]\nexpect = "rises"\nwobble = 1',
             "unknown key wobble")):
        bad_campaign(name, two + "[[trend]]\n%s\n" % trend, want)
    bad_campaign("trend = 5", "trend = 5\n" + two, "trend must be")
    add(C, "a tiny campaign", ["campaign", "c.toml", "-o", "out"] + QUIET["campaign"], 0,
        "1 runs", files=dict(frames, **{"c.toml": one}),
        checks=[status("out/runs/a/r1/summary.json", "completed"), exists("out/table.csv")])
    add(C, "a campaign with a failing run", ["campaign", "c.toml", "-o", "out"] + QUIET["campaign"],
        1, "bad replicate 1: failed", line="any",
        files={"scene.toml": scene({"run.frame_interval": "0.0"}), "fail.toml": scene(FAILING),
               "c.toml": one + '[[run]]\nname = "bad"\nscene = "fail.toml"\n'},
        checks=[status("out/runs/a/r1/summary.json", "completed"),
                status("out/runs/bad/r1/summary.json", "failed")])
    add(C, "a campaign run again (nothing to do)",
        ["campaign", "c.toml", "-o", "out"] + QUIET["campaign"], 0, "1 done before",
        files=dict(frames, **{"c.toml": one, "out/": lambda p: subprocess.run(
            [mesopen, "campaign", os.path.join(os.path.dirname(p), "c.toml"), "-o", p]
            + QUIET["campaign"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)}))
    long_campaign = {"scene.toml": scene(LONG),
                     "c.toml": one.replace("[[run]]", "frames = true\n[[run]]")}
    add(C, "a second campaign on a directory in use",
        ["campaign", "c.toml", "-o", "out"] + QUIET["campaign"], 1, "in use",
        files=long_campaign,
        during=(["campaign", "c.toml", "-o", "out"] + QUIET["campaign"],
                "out/runs/a/r1/vtk/frame_000001.vtu"))

    # -- dem and hybrid (LIGGGHTS) --------------------------------------------------------------
    E = "dem"
    dem = {"run.representation": '"dem"'}
    good_run(E, "dem: a tiny run", dem, checks=[exists("out/dem.data"),
                                                exists("out/vtk/disks_000000.vtu")])
    good_run(E, "hybrid: a tiny run", {"run.representation": '"hybrid"'})
    bad_scene(E, "dem.step longer than stable", scene(dict(dem, **{"dem.step": "1e-6"})),
              "dem.step")
    bad_scene(E, "dem.skin too large for the bins", scene(dict(dem, **{"dem.skin": "0.5"})),
              "dem.skin")
    add(E, "dem: output path with a space", ["run", "scene.toml", "-o", "o u t"] + QUIET["run"],
        2, "output directory without spaces", files={"scene.toml": scene(dem)})
    add(E, "dem: output path with $", ["run", "scene.toml", "-o", "o$ut"] + QUIET["run"],
        2, "output directory without spaces", files={"scene.toml": scene(dem)})
    bad_scene(E, "dem without grains", scene(dict(dem, **{"run.grains": "false"})),
              "run.representation")
    add(E, "campaign --representation dem: bad [dem] key", ["campaign", "c.toml", "-o", "out",
                                                          "--representation", "dem"]
        + QUIET["campaign"], 2, "dem.hertz_length",
        files={"scene.toml": scene({"dem.hertz_length": "1.0"}), "c.toml": one})

    # -- signals --------------------------------------------------------------------------------
    G = "signal"
    term, intr = signal.SIGTERM, signal.SIGINT
    trigger = "out/vtk/frame_000001.vtu"
    for name, changes, sig, code, text in (
            ("SIGTERM to run", LONG, term, 143, "SIGTERM"),
            ("SIGINT to run", LONG, intr, 130, "SIGINT"),
            ("SIGTERM to a dem run", dict(LONG, **dem), term, 143, "SIGTERM"),
            ("SIGINT to a hybrid run", dict(LONG, **{"run.representation": '"hybrid"'}), intr,
             130, "SIGINT")):
        add(G, name, cmd("run"), code, text, files={"scene.toml": scene(changes)},
            signals=(trigger, sig), checks=[status("out/summary.json", "interrupted")])
    add(G, "SIGTERM to a campaign", ["campaign", "c.toml", "-o", "out"] + QUIET["campaign"], 143,
        "interrupted", line="any", files=long_campaign,
        signals=("out/runs/a/r1/vtk/frame_000001.vtu", term),
        checks=[status("out/runs/a/r1/summary.json", "interrupted"), campaign_interrupted])
    return cases


# ---- running -----------------------------------------------------------------------------------

def make_files(d, files):
    for name, content in files.items():
        path = os.path.join(d, name.rstrip("/"))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        if name.endswith("/") and not callable(content):
            os.makedirs(path, exist_ok=True)
        elif callable(content):  # makes the file or directory itself
            content(path)
        else:
            with open(path, "wb") as f:
                f.write(content.encode() if isinstance(content, str) else content)


def wait_for(path, proc, limit):
    """Until `path` exists; False if `proc` ended first or the time ran out."""
    end = time.monotonic() + limit
    while time.monotonic() < end:
        if os.path.exists(path):
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.01)
    return False


def execute(mesopen, d, args, case):
    """Runs the case's command in d: (exit code, None after a hang; stdout; stderr; notes)."""
    notes = []
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen([mesopen] + args, cwd=d, stdout=out, stderr=err,
                                stdin=subprocess.DEVNULL)
        if case.signals:
            path, sig = case.signals
            if wait_for(os.path.join(d, path), proc, LIMIT / 2):
                proc.send_signal(sig)
            else:
                notes.append("ended or stalled before %s appeared: no signal sent" % path)
        try:
            code = proc.wait(timeout=LIMIT)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            code = None
        out.seek(0)
        err.seek(0)
        return code, out.read().decode(errors="replace"), err.read().decode(errors="replace"), notes


def run_case(mesopen, scratch, index, case):
    d = os.path.join(scratch, "%03d-%s" % (index, re.sub(r"[^A-Za-z0-9]+", "-", case.name)[:50]))
    os.makedirs(d)
    make_files(d, case.files)
    before = snapshot(d)
    background = None
    problems = []
    if case.during:
        words, path = case.during
        background = subprocess.Popen([mesopen] + words, cwd=d, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        if not wait_for(os.path.join(d, path), background, LIMIT / 2):
            problems.append("the command started first did not reach %s" % path)
    code, out, err, notes = execute(mesopen, d, case.args, case)
    problems += notes
    if background:
        background.send_signal(signal.SIGTERM)
        try:
            ended = background.wait(timeout=LIMIT)
        except subprocess.TimeoutExpired:
            background.kill()
            ended = background.wait()
        if ended != 143:
            problems.append("the command started first ended with %s, want 143" % ended)
    # the message: stderr's first line after a failure, stdout's after success (either when the
    # other is empty)
    first, second = (out, err) if code == 0 else (err, out)
    lines = [l for l in (first.strip() and first or second).splitlines() if l.strip()]
    first_line = lines[0].strip() if lines else ""
    if code is None:
        problems.append("did not end within %d s" % LIMIT)
    elif code < 0:
        problems.append("ended by signal %d" % -code)
    elif code != case.code:
        problems.append("exit %d, want %d" % (code, case.code))
    if case.line == "any":
        found = any(case.text in l for l in (out + "\n" + err).splitlines())
    else:
        found = case.text in first_line
    if not found:
        problems.append("message lacks %r" % case.text)
    if case.warn and case.warn not in err:
        problems.append("no warning with %r" % case.warn)
    if code is not None:
        problems += files_left(d, before, code)
        for check in case.checks:
            try:
                problems += check(d)
            except Exception as e:
                problems.append("check failed: %s" % e)
    return code, first_line, problems


def make_references(mesopen, scratch):
    """A finished tiny run, its target and a failed run, for the cases that read outputs."""
    ref = {name: os.path.join(scratch, "reference", name) for name in ("run", "target", "failed")}
    os.makedirs(os.path.dirname(ref["run"]))
    for name, command, changes, code in (("run", "run", {}, 0), ("target", "target", {}, 0),
                                         ("failed", "run", FAILING, 1)):
        path = ref[name] + ".toml"
        with open(path, "w") as f:
            f.write(scene(changes))
        p = subprocess.run([mesopen, command, path, "-o", ref[name]] + QUIET[command],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=LIMIT)
        if p.returncode != code:
            sys.exit("reference %s: exit %d, want %d" % (name, p.returncode, code))
    return ref


def main():
    mesopen, scratch = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    start = time.monotonic()
    ref = make_references(mesopen, scratch)
    cases = corpus(mesopen, ref) + generated_cases(mesopen)
    cases_dir = os.path.join(scratch, "cases")
    os.makedirs(cases_dir)
    def one(item):
        try:
            return run_case(mesopen, cases_dir, *item)
        except Exception as e:  # a case that cannot be set up or checked fails, the others go on
            return None, "", ["the case itself failed: %r" % e]

    with ThreadPoolExecutor(WORKERS) as pool:
        results = list(pool.map(one, enumerate(cases)))

    failures = 0
    row = "%-9s %-52s %5s  %-70s %s"
    print(row % ("category", "case", "exit", "first message line", "verdict"))
    for case, (code, first_line, problems) in zip(cases, results):
        verdict = "ok" if not problems else "FAIL: " + "; ".join(problems)
        failures += bool(problems)
        shown = first_line if len(first_line) <= 70 else first_line[:67] + "..."
        print(row % (case.category, case.name[:52], "-" if code is None else code, shown,
                     verdict))
    counts = {}
    for case in cases:
        counts[case.category] = counts.get(case.category, 0) + 1
    print("\n%d cases (%s): %d passed, %d failed, in %.0f s" % (
        len(cases), ", ".join("%s %d" % kv for kv in sorted(counts.items())),
        len(cases) - failures, failures, time.monotonic() - start))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
