"""CTest liggghts_vtk_files (labels liggghts, vtk): every VTK file of a small hybrid run (grains
near the path meshed, the others LIGGGHTS disks) and of its target reads back with VTK's own readers
(python3-vtk9) and holds what the HDF5 files hold, and a frame renders as ParaView shows it with
tools/paraview/show.py.

  - vtk/run.pvd: one time per frame of run.h5 (its time exactly), part 0 frame_NNNNNN.vtu and part 1
    disks_NNNNNN.vtu, times increasing; vtk/ holds those files and nothing else;
  - each frame_NNNNNN.vtu: parses; its points, velocities, body and cell arrays (the stress
    components under their run.h5 names sxx.. or the older stress_xx..) are finite and equal run.h5's
    /mesh and /frames/NNNNNN in single precision; one triangle per element not eroded, of /mesh's
    nodes, an empty cell per eroded one;
  - each disks_NNNNNN.vtu: one VTK_VERTEX per disk, radius > 0 and finite, radius, position, velocity
    and spin equal to /frames/NNNNNN/disks in single precision;
  - target.vtu (`mesopen target`): the meshed grains' and the projectile's triangles, points and body
    of target.h5, grain diameters finite, > 0 for grains;
  - show.py's plain-Python part reads run.pvd and the files' arrays as VTK does, and finds a field by
    either stress name; its ParaView part, run against a stand-in for paraview.simple that takes only
    ParaView 5.11's properties (fake_paraview.py; ParaView cannot be installed beside libvtk9-dev),
    builds the README's recipe (Extract Block /Root/Block1, Glyph 2D Glyph Circle, Scale Array radius,
    Scale Factor 2, All Points; the projectile body 0) and refuses what it should;
  - the last frame rendered off screen (under xvfb-run without a display): the grains coloured by the
    pressure, the projectile outlined, the disks as vtkGlyph3D of a unit-diameter circle
    (vtkRegularPolygonSource) scaled by radius x 2 (ParaView's recipe); the PNG is not blank: its
    disk-coloured pixels cover the disks' area (sum of pi r^2) and its other coloured pixels the
    elements' area, each within 20 %: the disks are drawn at their size (a scale factor of 1 draws
    them at half of it, a quarter of the area) and the grains are there.

    vtk_files.py MESOPEN SCRATCH_DIR           the test (the PNG stays in SCRATCH_DIR/frame.png)
    vtk_files.py --render PNG FRAME.vtu DISKS.vtu SUMMARY.json   the rendering, in its own process
"""
import contextlib
import io
import json
import math
import os
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ElementTree

import h5py
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools", "paraview"))
import show  # noqa: E402  (tools/paraview/show.py: its plain-Python part)

# The tiny hybrid scene of tests/liggghts/run.cpp (0.6 x 0.3 mm, 60 um grains, a 0.3 mm projectile,
# 20 ns) with a frame every 5 ns: five frames.
SCENE = """[target]
width = 0.6e-3
height = 0.3e-3
diameter = 60e-6
mesh_size = 15e-6
[projectile]
length = 0.3e-3
[run]
end_time = 2e-8
frame_interval = 5e-9
representation = "hybrid"
"""

# The FE frames' cell arrays: run.h5's names, and the VTK frames' older names of the stresses.
CELL_ARRAYS = ["sxx", "syy", "sxy", "szz", "pressure", "effective_stress", "plastic_strain"]

# Colours of the rendering, drawn unlit so that each is exact in the PNG.
BACKGROUND = (255, 255, 255)
SAND = (200, 168, 115)  # the disks
OUTLINE = (0, 0, 0)     # the projectile's outline

failures = []


def check(ok, message):
    """Record a failed check (the test goes on, to report every failure at once)."""
    if not ok:
        failures.append(message)
        print("FAIL: " + message, flush=True)
    return ok


def run(command, what, timeout=120):
    """Run a command; a non-zero exit ends the test with its output."""
    start = time.monotonic()
    p = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                       env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    print("%s: %.1f s" % (what, time.monotonic() - start), flush=True)
    if p.returncode != 0:
        sys.exit("%s: exit %d\n%s\n%s\n%s" % (what, p.returncode, " ".join(command), p.stdout,
                                               p.stderr))
    return p


class VtkErrors:
    """VTK's error and warning messages, caught instead of printed: a read that reports any fails."""

    def __init__(self):
        self.window = vtk.vtkStringOutputWindow()
        vtk.vtkOutputWindow.SetInstance(self.window)
        self.seen = 0

    def take(self):
        """The messages since the last call."""
        text = self.window.GetOutput()
        new, self.seen = text[self.seen:], len(text)
        return new.strip()


def read_vtu(path, errors):
    """The unstructured grid of a .vtu file, None (and a failure) if VTK does not read it whole."""
    reader = vtk.vtkXMLUnstructuredGridReader()
    messages = []

    @vtk.calldata_type(vtk.VTK_STRING)
    def caught(obj, event, message):
        messages.append(message.strip())
    reader.AddObserver("ErrorEvent", caught)
    reader.SetFileName(path)
    reader.Update()
    text = errors.take()
    if not check(not messages and not text and reader.GetErrorCode() == 0,
                 "%s: VTK's reader reports errors: %s %s" % (path, messages, text[:500])):
        return None
    return reader.GetOutput()


def array(data, name):
    """The named array of point or cell data as numpy, None if absent."""
    a = data.GetArray(name)
    return None if a is None else vtk_to_numpy(a)


def same(a, b, what):
    """a equals b (b rounded to single precision, as the VTK frames store it), shape and values."""
    b = np.asarray(b)
    if not check(a is not None, "%s: missing" % what):
        return False
    if not check(a.shape == b.shape, "%s: shape %s, expected %s" % (what, a.shape, b.shape)):
        return False
    if not check(np.all(np.isfinite(a)), "%s: %d values not finite"
                 % (what, np.count_nonzero(~np.isfinite(a)))):
        return False
    expected = b.astype(np.float32) if a.dtype == np.float32 else b
    bad = np.flatnonzero(a.ravel() != expected.ravel())
    return check(bad.size == 0, "%s: %d of %d values differ from the HDF5 file, first at %d: %r, "
                 "expected %r" % (what, bad.size, a.size, bad[0] if bad.size else -1,
                                  a.ravel()[bad[0]] if bad.size else None,
                                  expected.ravel()[bad[0]] if bad.size else None))


def points_of(grid):
    return vtk_to_numpy(grid.GetPoints().GetData())


def check_collection(out, h5):
    """run.pvd against run.h5's frames; returns [(index, time, frame file, disks file)]."""
    pvd = os.path.join(out, "vtk", "run.pvd")
    root = ElementTree.parse(pvd).getroot()
    datasets = root.findall("./Collection/DataSet")
    names = sorted(h5["frames"].keys())
    check(names == ["%06d" % i for i in range(len(names))],
          "run.h5's frames are not 000000..%06d: %s" % (len(names) - 1, names[:10]))
    check(len(names) >= 3, "run.h5 has %d frames, the scene makes 5" % len(names))
    check(len(datasets) == 2 * len(names), "run.pvd has %d DataSets for %d frames of run.h5 (a "
          "frame and the disks per frame)" % (len(datasets), len(names)))
    frames = []
    for i, name in enumerate(names):
        pair = datasets[2 * i:2 * i + 2]
        if not check(len(pair) == 2, "run.pvd has no DataSets for frame %s" % name):
            break
        time = h5["frames"][name].attrs["time"]
        for part, (d, stem) in enumerate(zip(pair, ("frame_", "disks_"))):
            check(d.get("part") == str(part) and d.get("file") == stem + name + ".vtu"
                  and float(d.get("timestep")) == time,
                  "run.pvd DataSet %s: expected part %d, file %s%s.vtu, timestep %r (run.h5)"
                  % (d.attrib, part, stem, name, time))
        frames.append((i, time, os.path.join(out, "vtk", "frame_%s.vtu" % name),
                       os.path.join(out, "vtk", "disks_%s.vtu" % name)))
    times = [f[1] for f in frames]
    check(all(a < b for a, b in zip(times, times[1:])), "run.pvd's times do not increase: %s"
          % times)
    listed = {"run.pvd"} | {os.path.basename(f[2]) for f in frames} | \
        {os.path.basename(f[3]) for f in frames}
    present = set(os.listdir(os.path.join(out, "vtk")))
    check(present == listed, "vtk/ holds %s beyond run.pvd's files, and lacks %s"
          % (sorted(present - listed), sorted(listed - present)))

    # show.py reads the same frames from run.pvd, with the run's directory as its argument.
    try:
        seen = show.read_collection(show.find_collection(out))
        check([(f.time, f.fe, f.disks) for f in seen] == [(t, a, b) for _, t, a, b in frames],
              "show.read_collection: %s, expected the frames of run.h5 %s" % (seen, frames))
    except show.RunFilesError as e:
        check(False, "show.py does not read run.pvd: %s" % e)
    return frames


def check_fe_frame(path, g, mesh, errors):
    """One frame_NNNNNN.vtu against run.h5's /mesh and /frames/NNNNNN (group g)."""
    grid = read_vtu(path, errors)
    if grid is None:
        return
    x, y = g["x"][()], g["y"][()]
    same(points_of(grid), np.stack([x, y, np.zeros_like(x)], axis=1), path + ": points")
    same(array(grid.GetPointData(), "velocity"),
         np.stack([g["vx"][()], g["vy"][()], np.zeros_like(x)], axis=1), path + ": velocity")
    triangles = mesh["triangles"][()]
    eroded = g["eroded"][()].astype(bool)
    n = len(triangles)
    check(grid.GetNumberOfCells() == n, "%s: %d cells, run.h5 has %d elements"
          % (path, grid.GetNumberOfCells(), n))
    types = vtk_to_numpy(grid.GetCellTypesArray())
    if check(types.shape == (n,), "%s: %d cell types for %d elements" % (path, types.size, n)):
        check(np.count_nonzero(types == vtk.VTK_TRIANGLE) == np.count_nonzero(~eroded),
              "%s: %d triangles, run.h5 has %d elements not eroded"
              % (path, np.count_nonzero(types == vtk.VTK_TRIANGLE), np.count_nonzero(~eroded)))
        check(np.all(types[eroded] == vtk.VTK_EMPTY_CELL) and
              np.all(types[~eroded] == vtk.VTK_TRIANGLE),
              "%s: cell types are not a triangle per element and an empty cell per eroded one"
              % path)
        cells = grid.GetCells()
        connectivity = vtk_to_numpy(cells.GetConnectivityArray())
        check(np.array_equal(connectivity, triangles[~eroded].ravel()),
              "%s: the triangles' nodes differ from run.h5's /mesh/triangles" % path)
    body = array(grid.GetCellData(), "body")
    same(body, mesh["element_body"][()].astype(body.dtype) if body is not None else None,
         path + ": body")
    check(body is not None and np.count_nonzero(body == 0) > 0 and body.max() >= 1,
          "%s: no projectile (body 0) or no grain (body >= 1)" % path)
    for name in CELL_ARRAYS:
        data = grid.GetCellData()
        vtk_name = name if data.HasArray(name) else show.FIELD_ALIASES.get(name, name)
        same(array(data, vtk_name), g[name][()], "%s: cell array %s" % (path, vtk_name))
    check_show_arrays(path, grid)


def check_disks(path, g, errors):
    """One disks_NNNNNN.vtu against run.h5's /frames/NNNNNN/disks (group g)."""
    grid = read_vtu(path, errors)
    if grid is None:
        return None
    radius_h5 = g["radius"][()]
    n = len(radius_h5)
    check(n > 10, "%s: run.h5 has %d disks, the hybrid scene more than 10" % (path, n))
    check(grid.GetNumberOfPoints() == n and grid.GetNumberOfCells() == n,
          "%s: %d points, %d cells for %d disks" % (path, grid.GetNumberOfPoints(),
                                                   grid.GetNumberOfCells(), n))
    types = vtk_to_numpy(grid.GetCellTypesArray())
    check(np.all(types == vtk.VTK_VERTEX), "%s: cells not all VTK_VERTEX: %s"
          % (path, sorted(set(types.tolist()))))
    check(np.array_equal(vtk_to_numpy(grid.GetCells().GetConnectivityArray()), np.arange(n)),
          "%s: vertex i is not point i" % path)
    radius = array(grid.GetPointData(), "radius")
    if check(radius is not None, "%s: no point array radius" % path):
        check(np.all(np.isfinite(radius)) and np.all(radius > 0),
              "%s: %d radii not finite or not > 0 (a glyph needs one)"
              % (path, np.count_nonzero(~(np.isfinite(radius) & (radius > 0)))))
    same(radius, radius_h5, path + ": radius")
    x, y = g["x"][()], g["y"][()]
    same(points_of(grid), np.stack([x, y, np.zeros_like(x)], axis=1), path + ": positions")
    same(array(grid.GetPointData(), "velocity"),
         np.stack([g["vx"][()], g["vy"][()], np.zeros_like(x)], axis=1), path + ": velocity")
    same(array(grid.GetPointData(), "omega"), g["omega"][()], path + ": omega")
    check_show_arrays(path, grid)
    return grid


def check_show_arrays(path, grid):
    """show.vtu_arrays (the XML header read in plain Python) lists the arrays VTK read."""
    def names(data):
        return [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]
    listed = show.vtu_arrays(path)
    check(sorted(listed["CELLS"]) == sorted(names(grid.GetCellData())) and
          sorted(listed["POINTS"]) == sorted(names(grid.GetPointData())),
          "%s: show.vtu_arrays gives %s; VTK reads cells %s, points %s"
          % (path, listed, names(grid.GetCellData()), names(grid.GetPointData())))


def check_show_fields(path):
    """show.choose_field finds the default field and a stress by either name, and refuses a field the
    frame has not, naming the arrays it has."""
    arrays = show.vtu_arrays(path)
    try:
        check(show.choose_field(show.DEFAULT_FIELD, arrays) == ("CELLS", show.DEFAULT_FIELD),
              "show.choose_field(%r) is not that cell array" % show.DEFAULT_FIELD)
        carried = "sxx" if "sxx" in arrays["CELLS"] else "stress_xx"
        for asked in ("sxx", "stress_xx"):
            check(show.choose_field(asked, arrays) == ("CELLS", carried),
                  "show.choose_field(%r) is not the cell array %s the frames carry"
                  % (asked, carried))
        check(show.choose_field("velocity", arrays) == ("POINTS", "velocity"),
              "show.choose_field('velocity') is not the point array")
    except show.RunFilesError as e:
        check(False, "show.choose_field: %s" % e)
    try:
        show.choose_field("no_such_field", arrays)
        check(False, "show.choose_field accepts a field the frames do not have")
    except show.RunFilesError as e:
        check("pressure" in str(e) and "no_such_field" in str(e),
              "show.choose_field's refusal does not name the arrays there are: %s" % e)
    a = show.parse_args(["RUN"])
    check(a.field == show.DEFAULT_FIELD and a.frame == -1 and a.screenshot is None,
          "show.py's defaults: field %s, frame %d, screenshot %s" % (a.field, a.frame, a.screenshot))


def check_target(target_dir, errors):
    """target.vtu against target.h5: the meshed grains' and the projectile's triangles."""
    path = os.path.join(target_dir, "target.vtu")
    grid = read_vtu(path, errors)
    if grid is None:
        return
    with h5py.File(os.path.join(target_dir, "target.h5"), "r") as h5:
        mesh, proj = h5["mesh"], h5["projectile"]
        x = np.concatenate([mesh["x"][()], proj["x"][()]])
        y = np.concatenate([mesh["y"][()], proj["y"][()]])
        tri_grains = mesh["tri"][()].reshape(-1, 3).astype(np.int64)
        tri_proj = proj["tri"][()].reshape(-1, 3).astype(np.int64) + len(mesh["x"])
        tri_offset = mesh["tri_offset"][()].astype(np.int64)
    same(points_of(grid), np.stack([x, y, np.zeros_like(x)], axis=1), path + ": points")
    n = len(tri_grains) + len(tri_proj)
    check(grid.GetNumberOfCells() == n, "%s: %d cells, target.h5 has %d + %d triangles"
          % (path, grid.GetNumberOfCells(), len(tri_grains), len(tri_proj)))
    types = vtk_to_numpy(grid.GetCellTypesArray())
    check(np.all(types == vtk.VTK_TRIANGLE), "%s: cells not all triangles" % path)
    check(np.array_equal(vtk_to_numpy(grid.GetCells().GetConnectivityArray()),
                         np.concatenate([tri_grains, tri_proj]).ravel()),
          "%s: the triangles' nodes differ from target.h5's" % path)
    body = array(grid.GetCellData(), "body")
    expected = np.concatenate([np.repeat(np.arange(1, len(tri_offset)), np.diff(tri_offset)),
                               np.zeros(len(tri_proj), dtype=np.int64)])
    same(body, expected.astype(body.dtype) if body is not None else None, path + ": body")
    diameter = array(grid.GetCellData(), "grain_diameter")
    if check(diameter is not None and diameter.shape == (n,),
             "%s: no grain_diameter per cell" % path):
        check(np.all(np.isfinite(diameter)) and np.all(diameter[:len(tri_grains)] > 0),
              "%s: grain diameters not finite or not > 0" % path)


def check_show_pipeline(out, scratch, frames):
    """show.show() and show.main() against a stand-in for paraview.simple that takes only ParaView
    5.11's properties (tests/liggghts/fake_paraview.py): the recipe of the README, in a run with
    disks and in one without, and the refusals."""
    import fake_paraview
    png = os.path.join(scratch, "show.png")
    try:
        fake = fake_paraview.install()
        try:
            show.show(out, screenshot=png)
        except Exception as e:  # any error is the finding
            check(False, "show.show(%s) fails against ParaView 5.11's proxies: %r" % (out, e))
            return
        blocks = fake.of_kind("ExtractBlock")
        check(sorted(tuple(b.Selectors) for b in blocks) == [("/Root/Block0",), ("/Root/Block1",)],
              "show.py extracts the blocks %s, not /Root/Block0 (FE) and /Root/Block1 (disks)"
              % [b.Selectors for b in blocks])
        glyphs = fake.of_kind("Glyph")
        if check(len(glyphs) == 1, "show.py makes %d Glyphs, not one" % len(glyphs)):
            g = glyphs[0]
            recipe = {"GlyphType": ("2D Glyph", "Circle", 1), "Input": "/Root/Block1",
                      "OrientationArray": ["POINTS", "No orientation array"],
                      "ScaleArray": ["POINTS", "radius"], "ScaleFactor": 2.0,
                      "GlyphMode": "All Points"}
            made = {"GlyphType": (g.GlyphType.kind, g.GlyphType.GlyphType, g.GlyphType.Filled),
                    "Input": g.Input.Selectors[0] if g.Input.kind == "ExtractBlock" else g.Input,
                    "OrientationArray": g.OrientationArray, "ScaleArray": g.ScaleArray,
                    "ScaleFactor": g.ScaleFactor, "GlyphMode": g.GlyphMode}
            check(made == recipe, "show.py's disk Glyph is %s, not %s" % (made, recipe))
        ranges = sorted((t.LowerThreshold, t.UpperThreshold, t.Scalars[1], t.Input.kind)
                        for t in fake.of_kind("Threshold"))
        check(len(ranges) == 2 and ranges[0][:2] == (-0.5, 0.5) and ranges[1][0] == 0.5 and
              all(r[2:] == ("body", "ExtractBlock") for r in ranges),
              "show.py's Thresholds on the FE block are %s, not body 0 and body >= 1" % ranges)
        coloured = [v for _, v in fake.colored if v is not None]
        check(coloured == [("CELLS", "pressure")] * 2, "show.py colours by %s, not the grains and "
              "the projectile by the cell array pressure" % coloured)
        scene = fake.of_kind("AnimationScene")
        check(scene and scene[-1].AnimationTime == frames[-1][1],
              "show.py shows time %s, not the last frame's %r"
              % (scene[-1].properties if scene else None, frames[-1][1]))
        check(fake.screenshots == [(png, [1600, 900])], "show.py's screenshots: %s"
              % fake.screenshots)

        # A stress component under either name, and frame 0.
        fake = fake_paraview.install()
        show.show(out, field="stress_xx", frame=0)
        carried = "sxx" if "sxx" in show.vtu_arrays(frames[0][2])["CELLS"] else "stress_xx"
        coloured = [v for _, v in fake.colored if v is not None]
        check(coloured == [("CELLS", carried)] * 2, "show.py --field stress_xx colours by %s, not "
              "the cell array %s the frames carry" % (coloured, carried))
        check(fake.of_kind("AnimationScene")[-1].AnimationTime == frames[0][1],
              "show.py --frame 0 does not show the first frame's time")

        # A run without disks: run.pvd of part 0 only; the reader's output is the FE grid itself.
        fe_only = os.path.join(scratch, "fe_only", "vtk")
        os.makedirs(fe_only, exist_ok=True)
        with open(os.path.join(fe_only, "run.pvd"), "w") as f:
            f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                    '  <Collection>\n%s  </Collection>\n</VTKFile>\n'
                    % "".join('    <DataSet timestep="%.17g" part="0" file="%s"/>\n'
                              % (t, os.path.relpath(fe, fe_only)) for _, t, fe, _ in frames))
        fake = fake_paraview.install()
        show.show(os.path.dirname(fe_only))
        check(not fake.of_kind("ExtractBlock") and not fake.of_kind("Glyph") and
              all(t.Input.kind == "PVDReader" for t in fake.of_kind("Threshold")),
              "show.py on a run without disks: %s" % [p.kind for p in fake.created])

        # Refusals: a field the frames have not, a frame past the last, ParaView before 5.10.
        for kwargs, words in (({"field": "no_such"}, "no_such"), ({"frame": len(frames)}, "frame"),
                              ({"disk_field": "nothing"}, "nothing")):
            fake_paraview.install()
            try:
                show.show(out, **kwargs)
                check(False, "show.show(%s) accepted" % kwargs)
            except show.RunFilesError as e:
                check(words in str(e), "show.show(%s): %s" % (kwargs, e))
        fake_paraview.install(version=(5, 9))
        try:
            show.show(out)
            check(False, "show.show accepted ParaView 5.9")
        except show.RunFilesError as e:
            check("5.10" in str(e), "show.show on ParaView 5.9: %s" % e)

        # The command line: a screenshot (exit 0), no window to interact with (exit 2), --list.
        fake_paraview.install()
        check(show.main([out, "--screenshot", png]) == 0, "show.py --screenshot does not exit 0")
        fake_paraview.install()
        check(show.main([out]) == 2, "show.py without a window (pvbatch) does not exit 2")
        listing = io.StringIO()
        with contextlib.redirect_stdout(listing):
            code = show.main([out, "--list"])
        check(code == 0 and "%d frames, with disks" % len(frames) in listing.getvalue() and
              "radius" in listing.getvalue(),
              "show.py --list: exit %d, printed %r" % (code, listing.getvalue()[:300]))
        check(show.main([os.path.join(scratch, "nowhere")]) == 2,
              "show.py on a directory without run.pvd does not exit 2")
    finally:
        sys.modules.pop("paraview", None)
        sys.modules.pop("paraview.simple", None)


# ---- rendering ---------------------------------------------------------------------------------

def flat(actor, rgb=None):
    """Unlit: a surface's colour is its colour map's or `rgb`, exactly."""
    p = actor.GetProperty()
    p.SetAmbient(1.0)
    p.SetDiffuse(0.0)
    p.SetSpecular(0.0)
    if rgb is not None:
        p.SetColor(*[c / 255.0 for c in rgb])
    return actor


def threshold(grid, lower, upper):
    """The cells of `grid` whose body is in [lower, upper], as data (a filter whose Python object is
    gone while a pipeline still uses it crashes VTK)."""
    t = vtk.vtkThreshold()
    t.SetInputData(grid)
    t.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_CELLS, "body")
    t.SetLowerThreshold(lower)
    t.SetUpperThreshold(upper)
    t.SetThresholdFunction(vtk.vtkThreshold.THRESHOLD_BETWEEN)
    t.Update()
    return t.GetOutput()


def render(png, frame_vtu, disks_vtu, summary_path):
    """The frame as show.py shows it in ParaView, off screen, to `png`; what the picture should hold
    (the pixel size, the disks' and the elements' areas) to `summary_path`."""
    errors = VtkErrors()
    fe = read_vtu(frame_vtu, errors)
    disks = read_vtu(disks_vtu, errors)
    if fe is None or disks is None:
        sys.exit("render: %s" % "; ".join(failures))
    _, field = show.choose_field(show.DEFAULT_FIELD, show.vtu_arrays(frame_vtu))
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(*[c / 255.0 for c in BACKGROUND])

    # Grains and projectile coloured by the field (one colour map, blue to red), the projectile
    # outlined in black.
    low, high = fe.GetCellData().GetArray(field).GetRange()
    lut = vtk.vtkLookupTable()
    lut.SetHueRange(0.667, 0.0)
    lut.Build()
    for lower, upper in ((0.5, 2.0**31), (-0.5, 0.5)):
        mapper = vtk.vtkDataSetMapper()
        mapper.SetInputData(threshold(fe, lower, upper))
        mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray(field)
        mapper.SetLookupTable(lut)
        mapper.SetScalarRange(low, high if high > low else low + 1.0)
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        renderer.AddActor(flat(actor))
    surface = vtk.vtkGeometryFilter()
    surface.SetInputData(threshold(fe, -0.5, 0.5))
    edges = vtk.vtkFeatureEdges()
    edges.SetInputConnection(surface.GetOutputPort())
    edges.BoundaryEdgesOn()
    edges.FeatureEdgesOff()
    edges.NonManifoldEdgesOff()
    edges.ManifoldEdgesOff()
    edges.ColoringOff()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(edges.GetOutputPort())
    mapper.ScalarVisibilityOff()
    outline = flat(vtk.vtkActor(), OUTLINE)
    outline.SetMapper(mapper)
    outline.GetProperty().SetLineWidth(2.0)
    renderer.AddActor(outline)

    # The disks: ParaView's recipe (Glyph, 2D Glyph "Circle" of unit diameter, Scale Array radius,
    # Scale Factor 2, All Points) as VTK: a circle of radius 0.5 glyphed at every point, scaled by
    # the scalar radius x 2.
    circle = vtk.vtkRegularPolygonSource()
    circle.SetNumberOfSides(48)
    circle.SetRadius(0.5)
    circle.GeneratePolygonOn()
    circle.GeneratePolylineOff()
    glyph = vtk.vtkGlyph3D()
    glyph.SetInputData(disks)
    glyph.SetSourceConnection(circle.GetOutputPort())
    glyph.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS, "radius")
    glyph.SetScaleModeToScaleByScalar()
    glyph.SetScaleFactor(2.0)
    glyph.ClampingOff()
    glyph.OrientOff()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(glyph.GetOutputPort())
    mapper.ScalarVisibilityOff()
    circles = flat(vtk.vtkActor(), SAND)
    circles.SetMapper(mapper)
    renderer.AddActor(circles)

    # The whole model in view, parallel projection; the window has the model's aspect.
    glyph.Update()
    box = vtk.vtkBoundingBox()
    box.AddBounds(fe.GetBounds())
    box.AddBounds(glyph.GetOutput().GetBounds())
    (x0, x1), (y0, y1) = (box.GetBound(0), box.GetBound(1)), (box.GetBound(2), box.GetBound(3))
    width = 1200
    height = int(min(max(width * (y1 - y0) / (x1 - x0), 300), 1200))
    half_height = 1.05 * max((y1 - y0) / 2, (x1 - x0) / 2 * height / width)
    camera = renderer.GetActiveCamera()
    camera.ParallelProjectionOn()
    camera.SetFocalPoint((x0 + x1) / 2, (y0 + y1) / 2, 0.0)
    camera.SetPosition((x0 + x1) / 2, (y0 + y1) / 2, 1.0)
    camera.SetViewUp(0.0, 1.0, 0.0)
    camera.SetParallelScale(half_height)
    renderer.ResetCameraClippingRange()

    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)  # no blending at the edges: colours stay exact
    window.AddRenderer(renderer)
    window.SetSize(width, height)
    window.Render()
    image = vtk.vtkWindowToImageFilter()
    image.SetInput(window)
    image.ReadFrontBufferOff()
    image.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(png)
    writer.SetInputConnection(image.GetOutputPort())
    writer.Write()

    # What the picture should hold: pixel size, the disks' area and the elements' (not eroded).
    radius = vtk_to_numpy(disks.GetPointData().GetArray("radius")).astype(float)
    p = points_of(fe).astype(float)
    types = vtk_to_numpy(fe.GetCellTypesArray())
    tri = vtk_to_numpy(fe.GetCells().GetConnectivityArray()).reshape(-1, 3)
    a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    fe_area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) -
                           (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])).sum()
    with open(summary_path, "w") as f:
        json.dump({"pixel": 2 * half_height / height, "disks_area": float(np.sum(math.pi * radius**2)),
                   "fe_area": float(fe_area), "triangles": int(np.count_nonzero(types == 5)),
                   "field": field, "errors": errors.take()}, f)


def check_png(png, summary):
    """The rendered frame is not blank: disks and elements cover their areas, the field has colours."""
    reader = vtk.vtkPNGReader()
    reader.SetFileName(png)
    reader.Update()
    image = reader.GetOutput()
    w, h, _ = image.GetDimensions()
    rgb = vtk_to_numpy(image.GetPointData().GetScalars())[:, :3].astype(int)
    check(w * h > 0 and rgb.shape[0] == w * h, "%s: not an image of its size (%d x %d)" % (png, w, h))

    def count(colour):
        return int(np.count_nonzero(np.all(rgb == colour, axis=1)))
    background, sand, black = count(BACKGROUND), count(SAND), count(OUTLINE)
    coloured = rgb.shape[0] - background - sand - black
    pixel_area = summary["pixel"] ** 2
    disks = summary["disks_area"] / pixel_area
    fe = summary["fe_area"] / pixel_area
    print("rendered %s (%d x %d): background %d, disks %d pixels (their area: %.0f), projectile "
          "outline %d, grains and projectile %d (their area: %.0f), %d colours"
          % (png, w, h, background, sand, disks, black, coloured, fe,
             len(np.unique(rgb, axis=0))), flush=True)
    check(background < rgb.shape[0], "%s: blank, background only" % png)
    check(0.8 < sand / disks < 1.2, "%s: the disks cover %d pixels, their area is %.0f: not drawn "
          "at their radius" % (png, sand, disks))
    check(0.8 < (coloured + black) / fe < 1.2, "%s: the elements cover %d pixels, their area is "
          "%.0f" % (png, coloured + black, fe))
    check(black > 100, "%s: the projectile's outline has %d pixels" % (png, black))
    # The field's colour map: several colours among the elements' pixels.
    others = rgb[~(np.all(rgb == BACKGROUND, axis=1) | np.all(rgb == SAND, axis=1) |
                   np.all(rgb == OUTLINE, axis=1))]
    check(len(np.unique(others, axis=0)) >= 3, "%s: the elements have %d colours (%s)"
          % (png, len(np.unique(others, axis=0)), summary["field"]))


def main():
    if sys.argv[1] == "--render":
        render(*sys.argv[2:6])
        return
    mesopen, scratch = sys.argv[1], sys.argv[2]
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    scene = os.path.join(scratch, "scene.toml")
    with open(scene, "w") as f:
        f.write(SCENE)
    out, target = os.path.join(scratch, "run"), os.path.join(scratch, "target")
    run([mesopen, "target", scene, "-o", target, "--threads", "1", "--no-plot"], "mesopen target")
    run([mesopen, "run", scene, "-o", out, "--threads", "1", "--quiet"], "mesopen run")

    errors = VtkErrors()
    with h5py.File(os.path.join(out, "run.h5"), "r") as h5:
        frames = check_collection(out, h5)
        check_show_fields(frames[0][2])
        for i, _, fe, disks in frames:
            g = h5["frames"]["%06d" % i]
            check_fe_frame(fe, g, h5["mesh"], errors)
            if check("disks" in g, "run.h5 frame %06d has no disks" % i):
                check_disks(disks, g["disks"], errors)
    check_target(target, errors)
    print("read %d frames, %d disk files and target.vtu" % (len(frames), len(frames)), flush=True)
    check_show_pipeline(out, scratch, frames)

    # The last frame rendered in a process of its own (a crash of the OpenGL stack is reported, not
    # fatal to the checks above), under a virtual X server if there is no display.
    png, summary_path = os.path.join(scratch, "frame.png"), os.path.join(scratch, "frame.json")
    command = [sys.executable, os.path.abspath(__file__), "--render", png, frames[-1][2],
               frames[-1][3], summary_path]
    if not os.environ.get("DISPLAY"):
        if shutil.which("xvfb-run") is None:
            sys.exit("no DISPLAY and no xvfb-run: install xvfb and xauth (tools/setup.sh lists them)")
        command = ["xvfb-run", "-a", "-s", "-screen 0 1600x1200x24"] + command
    run(command, "rendering the last frame", timeout=120)
    with open(summary_path) as f:
        summary = json.load(f)
    check(summary["errors"] == "", "VTK reported while rendering: %s" % summary["errors"][:500])
    check_png(png, summary)

    if failures:
        sys.exit("%d checks failed:\n  %s" % (len(failures), "\n  ".join(failures)))
    print("all checks passed; the rendered frame: %s" % png)


if __name__ == "__main__":
    main()
