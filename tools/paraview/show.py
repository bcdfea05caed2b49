"""Show a `mesopen run` in ParaView: the grains and the projectile coloured by a field, the
projectile outlined, the DEM disks as circles of their radius, a colour legend, and optionally a
screenshot.

    pvpython tools/paraview/show.py RUN_DIR [--field pressure] [--frame -1] [--screenshot out.png]
    pvbatch tools/paraview/show.py RUN_DIR --screenshot out.png     (no window; e.g. on a cluster)
    python3 tools/paraview/show.py RUN_DIR --list                   (frames and arrays; no ParaView)

RUN_DIR is the run's directory (or its vtk/ folder, or vtk/run.pvd). Without --screenshot,
pvpython opens an interactive window (q closes it). In ParaView's GUI (View > Python Shell):

    import sys; sys.path.insert(0, "/path/to/mesopen/tools/paraview"); import show
    show.show("/path/to/RUN_DIR", field="effective_stress")

The pipeline it builds (ParaView 5.10 or later; written against 5.11's paraview.simple):
  run.pvd (PVD Reader): each time holds part 0, the FE bodies (frame_NNNNNN.vtu), and in dem and
  hybrid runs part 1, the disks (disks_NNNNNN.vtu); with two parts the reader gives a multiblock
  whose blocks are /Root/Block0 and /Root/Block1 (the .pvd names no blocks).
  - Extract Block /Root/Block0 -> Threshold body >= 1 (the grains) and Threshold body = 0 (the
    projectile, and an Extract Surface -> Feature Edges outline of it drawn in black), both
    coloured by --field with one colour map;
  - Extract Block /Root/Block1 -> Glyph: Glyph Type "2D Glyph", its type "Circle" (filled), Scale
    Array radius, Scale Factor 2 (ParaView's circle glyph has unit diameter), Glyph Mode "All
    Points" (the default mode samples a few thousand points only), no orientation array.
A Glyph applied to run.pvd itself would glyph every FE node too, and at the default scale factor
(a tenth of the data's size over the radius) the circles are far too big or too small.

The parts that need no ParaView (finding the files, reading run.pvd, listing a frame's arrays,
choosing the field) are plain Python, importable with /usr/bin/python3 and tested by CTest
liggghts_vtk_files (tests/liggghts/vtk_files.py).
"""
import argparse
import importlib
import math
import os
import re
import sys
import xml.etree.ElementTree as ElementTree

# The field the grains are coloured by unless --field says otherwise: the pressure (compression
# positive) shows the force chains through the grains.
DEFAULT_FIELD = "pressure"

# The stress components are named as in run.h5 (sxx, syy, sxy, szz); VTK frames written before
# they took those names call them stress_xx, stress_yy, stress_xy, stress_zz. Either name finds
# whichever the files carry.
FIELD_ALIASES = {"sxx": "stress_xx", "syy": "stress_yy", "sxy": "stress_xy", "szz": "stress_zz"}
FIELD_ALIASES.update({old: new for new, old in list(FIELD_ALIASES.items())})

# What the arrays hold, for the legend's title.
FIELD_UNITS = {"sxx": "Pa", "syy": "Pa", "sxy": "Pa", "szz": "Pa", "stress_xx": "Pa",
               "stress_yy": "Pa", "stress_xy": "Pa", "stress_zz": "Pa", "pressure": "Pa",
               "effective_stress": "Pa", "plastic_strain": "", "body": "", "velocity": "m/s",
               "radius": "m", "omega": "rad/s"}

# The blocks of run.pvd as ParaView's PVD reader gives them when a time has two parts.
FE_SELECTOR = "/Root/Block0"
DISKS_SELECTOR = "/Root/Block1"


class RunFilesError(Exception):
    """The run's VTK files are missing or not as `mesopen run` writes them; the message says which."""


class Frame:
    """One time of run.pvd: its time [s], the FE bodies' file, the disks' file (None without)."""

    def __init__(self, time, fe, disks):
        self.time, self.fe, self.disks = time, fe, disks

    def __repr__(self):
        return "Frame(time=%r, fe=%r, disks=%r)" % (self.time, self.fe, self.disks)


def find_collection(path):
    """The path of run.pvd given a run directory, its vtk/ folder or the .pvd file itself."""
    for candidate in (path, os.path.join(path, "run.pvd"), os.path.join(path, "vtk", "run.pvd")):
        if os.path.isfile(candidate) and candidate.endswith(".pvd"):
            return candidate
    raise RunFilesError("no run.pvd at %s, %s nor %s (a `mesopen run` output directory has "
                        "vtk/run.pvd unless run.vtk = false or run.frame_interval = 0)"
                        % (path, os.path.join(path, "run.pvd"), os.path.join(path, "vtk", "run.pvd")))


def read_collection(pvd):
    """The frames of run.pvd in time order: part 0 of each time is the FE bodies, part 1 (dem and
    hybrid runs) the disks. The times must differ (ParaView's reader would show every part of equal
    times as one frame) and every time must have its FE part, and its disks if any time has them."""
    try:
        root = ElementTree.parse(pvd).getroot()
    except (OSError, ElementTree.ParseError) as e:
        raise RunFilesError("%s: not readable as XML: %s" % (pvd, e))
    collection = root.find("Collection")
    if root.tag != "VTKFile" or root.get("type") != "Collection" or collection is None:
        raise RunFilesError("%s: not a VTK collection (<VTKFile type=\"Collection\">"
                            "<Collection>)" % pvd)
    folder = os.path.dirname(os.path.abspath(pvd))
    parts = {}  # timestep text -> {part: file}
    for dataset in collection.findall("DataSet"):
        timestep, part, name = dataset.get("timestep"), dataset.get("part", "0"), dataset.get("file")
        if timestep is None or name is None:
            raise RunFilesError("%s: a DataSet without timestep or file: %s"
                                % (pvd, ElementTree.tostring(dataset, encoding="unicode").strip()))
        if part not in ("0", "1"):
            raise RunFilesError("%s: part %s of time %s (only 0, the FE bodies, and 1, the disks)"
                                % (pvd, part, timestep))
        at = parts.setdefault(timestep, {})
        if part in at:
            raise RunFilesError("%s: time %s has part %s twice (%s and %s)"
                                % (pvd, timestep, part, at[part], name))
        at[part] = os.path.join(folder, name)
    if not parts:
        raise RunFilesError("%s: no frames" % pvd)
    frames = []
    for timestep, at in parts.items():
        try:
            time = float(timestep)
        except ValueError:
            raise RunFilesError("%s: timestep %r is not a number" % (pvd, timestep))
        if not math.isfinite(time):
            raise RunFilesError("%s: timestep %r is not finite" % (pvd, timestep))
        if "0" not in at:
            raise RunFilesError("%s: time %s has no part 0 (the FE bodies)" % (pvd, timestep))
        frames.append(Frame(time, at["0"], at.get("1")))
    frames.sort(key=lambda f: f.time)
    for a, b in zip(frames, frames[1:]):
        if a.time == b.time:  # two texts of one number, e.g. 1e-7 and 1.0e-7
            raise RunFilesError("%s: two frames at time %r" % (pvd, a.time))
    with_disks = [f.disks is not None for f in frames]
    if any(with_disks) and not all(with_disks):
        missing = [f.time for f in frames if f.disks is None]
        raise RunFilesError("%s: the disks (part 1) are missing at times %s" % (pvd, missing[:5]))
    return frames


def vtu_arrays(vtu):
    """The arrays of a .vtu file as {"CELLS": [names], "POINTS": [names]}, read from its XML header
    (the appended binary data after <AppendedData> is not read)."""
    try:
        with open(vtu, "rb") as f:
            head = b""
            while b"<AppendedData" not in head:
                chunk = f.read(1 << 16)
                if not chunk:
                    break
                head += chunk
    except OSError as e:
        raise RunFilesError("%s: cannot read: %s" % (vtu, e))
    text = head.split(b"<AppendedData")[0].decode("utf-8", "replace")
    if "<VTKFile" not in text or "UnstructuredGrid" not in text:
        raise RunFilesError("%s: not a VTK unstructured grid (.vtu) file" % vtu)
    arrays = {}
    for association, tag in (("CELLS", "CellData"), ("POINTS", "PointData")):
        section = re.search(r"<%s\b[^>]*>(.*?)</%s>" % (tag, tag), text, re.S)
        arrays[association] = (re.findall(r"<DataArray\b[^>]*\bName=\"([^\"]*)\"", section.group(1))
                               if section else [])
    return arrays


def choose_field(requested, arrays, what="the FE frames"):
    """(association, name) of the array to colour by: `requested` as a cell array of the file
    (arrays: vtu_arrays of it), else as a point array (velocity), else by its other name (sxx <->
    stress_xx). Raises RunFilesError naming the arrays there are."""
    for name in (requested, FIELD_ALIASES.get(requested)):
        for association in ("CELLS", "POINTS"):
            if name is not None and name in arrays.get(association, []):
                return association, name
    raise RunFilesError("no array %r in %s; cell arrays: %s; point arrays: %s"
                        % (requested, what, ", ".join(arrays.get("CELLS", [])) or "none",
                           ", ".join(arrays.get("POINTS", [])) or "none"))


def choose_frame(frames, index):
    """The frame of that index (negative from the end: -1 is the last)."""
    if not -len(frames) <= index < len(frames):
        raise RunFilesError("frame %d: the run has %d frames (0 to %d, or -1 for the last)"
                            % (index, len(frames), len(frames) - 1))
    return frames[index]


def legend_title(name):
    """The colour legend's title: the array's name and its unit."""
    unit = FIELD_UNITS.get(name, "")
    return "%s [%s]" % (name, unit) if unit else name


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="show.py", description="Show a mesopen run's VTK frames in ParaView: grains and "
        "projectile coloured by a field, the projectile outlined, the disks as circles.")
    p.add_argument("run", help="the run's directory (or its vtk/ folder, or vtk/run.pvd)")
    p.add_argument("--field", default=DEFAULT_FIELD,
                   help="cell array of the FE frames to colour by (default %(default)s; e.g. "
                   "effective_stress, plastic_strain, sxx, syy, sxy, szz, body) or the point "
                   "array velocity")
    p.add_argument("--frame", type=int, default=-1,
                   help="the frame shown, from 0 (default -1: the last)")
    p.add_argument("--range", type=float, nargs=2, metavar=("MIN", "MAX"),
                   help="the colour map's range (default: the frame's data range)")
    p.add_argument("--colormap", help="a ParaView colour map preset, e.g. 'Viridis (matplotlib)' "
                   "(default: ParaView's default)")
    p.add_argument("--disk-field", help="point array of the disks to colour them by (radius, "
                   "omega, velocity; default: one colour)")
    p.add_argument("--screenshot", metavar="PNG", help="save the view to this PNG")
    p.add_argument("--size", type=int, nargs=2, default=[1600, 900], metavar=("WIDTH", "HEIGHT"),
                   help="the view's size in pixels (default %(default)s)")
    p.add_argument("--list", action="store_true",
                   help="print the frames and the arrays, and exit (needs no ParaView)")
    a = p.parse_args(argv)
    if a.size[0] < 16 or a.size[1] < 16:
        p.error("--size: at least 16 x 16 pixels")
    if a.range is not None and not a.range[0] < a.range[1]:
        p.error("--range: MIN must be below MAX")
    return a


def describe(frames, arrays):
    """Lines for --list: the frames and the FE frames' and disks' arrays."""
    lines = ["%d frames, %s" % (len(frames), "with disks" if frames[0].disks else "no disks")]
    for i, f in enumerate(frames):
        lines.append("  %3d  t = %-12.6g %s%s" % (i, f.time, os.path.basename(f.fe),
                                                  "  " + os.path.basename(f.disks) if f.disks else ""))
    lines.append("FE cell arrays: " + ", ".join(arrays["CELLS"]))
    lines.append("FE point arrays: " + ", ".join(arrays["POINTS"]))
    if frames[0].disks:
        lines.append("disks' point arrays: " + ", ".join(vtu_arrays(frames[0].disks)["POINTS"]))
    return lines


# ---- ParaView ---------------------------------------------------------------------------------

def _threshold(pv, source, name, lower, upper):
    """Threshold of the cell array body in [lower, upper] (ParaView 5.10's properties)."""
    t = pv.Threshold(registrationName=name, Input=source)
    t.Scalars = ["CELLS", "body"]
    t.LowerThreshold = lower
    t.UpperThreshold = upper
    t.ThresholdMethod = "Between"
    return t


def show(run, field=DEFAULT_FIELD, frame=-1, screenshot=None, size=(1600, 900), value_range=None,
         colormap=None, disk_field=None):
    """Build the pipeline in the active ParaView session and render frame `frame`; save the view
    to `screenshot` (a PNG) when given. Returns the render view."""
    from paraview import simple as pv

    version = pv.GetParaViewVersion()
    if (version.major, version.minor) < (5, 10):
        raise RunFilesError("ParaView %d.%d: show.py needs 5.10 or later (Extract Block by "
                            "selectors, Threshold's lower and upper thresholds)"
                            % (version.major, version.minor))
    pvd = find_collection(run)
    frames = read_collection(pvd)
    shown = choose_frame(frames, frame)
    association, name = choose_field(field, vtu_arrays(shown.fe))
    disks = shown.disks is not None
    if disk_field is not None:
        if not disks:
            raise RunFilesError("--disk-field %s: this run has no disks" % disk_field)
        disk_field = choose_field(disk_field, vtu_arrays(shown.disks), "the disks' files")[1]

    view = pv.GetActiveViewOrCreate("RenderView")
    view.ViewSize = list(size)
    view.InteractionMode = "2D"  # the model is plane strain in x, y
    view.OrientationAxesVisibility = 0

    reader = pv.PVDReader(registrationName="run.pvd", FileName=pvd)
    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = shown.time
    view.ViewTime = shown.time

    # With disks the reader gives a multiblock (part 0, part 1); without, the FE grid itself.
    if disks:
        fe = pv.ExtractBlock(registrationName="FE bodies", Input=reader)
        fe.Selectors = [FE_SELECTOR]
    else:
        fe = reader
    # Body 0 is the projectile, body b >= 1 the grain b - 1.
    grains = _threshold(pv, fe, "grains", 0.5, 2.0**31)
    projectile = _threshold(pv, fe, "projectile", -0.5, 0.5)

    coloured = []
    for source in (grains, projectile):
        d = pv.Show(source, view)
        d.SetRepresentationType("Surface")
        if association == "POINTS":  # velocity: its magnitude
            pv.ColorBy(d, (association, name, "Magnitude"))
        else:
            pv.ColorBy(d, (association, name))
        coloured.append(d)
    # The projectile's outline, drawn over the colours, tells it from the grains.
    outline = pv.FeatureEdges(registrationName="projectile outline",
                              Input=pv.ExtractSurface(registrationName="projectile surface",
                                                      Input=projectile))
    outline.BoundaryEdges = 1
    outline.FeatureEdges = 0
    outline.NonManifoldEdges = 0
    outline.ManifoldEdges = 0
    o = pv.Show(outline, view)
    pv.ColorBy(o, None)
    o.AmbientColor = o.DiffuseColor = [0.0, 0.0, 0.0]
    o.LineWidth = 2.0

    lut = pv.GetColorTransferFunction(name)
    if colormap:
        lut.ApplyPreset(colormap, True)
    if value_range:
        lut.AutomaticRescaleRangeMode = "Never"
        lut.RescaleTransferFunction(value_range[0], value_range[1])
        pv.GetOpacityTransferFunction(name).RescaleTransferFunction(value_range[0], value_range[1])
    else:  # the range of the FE bodies (grains and projectile) at this frame
        fe.UpdatePipeline(shown.time)
        data = fe.CellData if association == "CELLS" else fe.PointData
        low, high = data[name].GetRange(-1 if association == "POINTS" else 0)
        if not high > low:  # one value everywhere (e.g. 0 at the start): a range around it
            low, high = low - 1.0, high + 1.0
        lut.RescaleTransferFunction(low, high)
        pv.GetOpacityTransferFunction(name).RescaleTransferFunction(low, high)
    coloured[0].SetScalarBarVisibility(view, True)
    bar = pv.GetScalarBar(lut, view)
    bar.Title = legend_title(name)
    bar.ComponentTitle = "magnitude" if association == "POINTS" else ""

    if disks:
        block = pv.ExtractBlock(registrationName="disks", Input=reader)
        block.Selectors = [DISKS_SELECTOR]
        circles = pv.Glyph(registrationName="disk circles", Input=block, GlyphType="2D Glyph")
        circles.GlyphType.GlyphType = "Circle"
        circles.GlyphType.Filled = 1
        circles.OrientationArray = ["POINTS", "No orientation array"]
        circles.ScaleArray = ["POINTS", "radius"]
        circles.ScaleFactor = 2.0  # the circle glyph's diameter is 1: 2 x radius
        circles.GlyphMode = "All Points"
        c = pv.Show(circles, view)
        if disk_field:
            pv.ColorBy(c, ("POINTS", disk_field, "Magnitude") if disk_field == "velocity"
                       else ("POINTS", disk_field))
            c.RescaleTransferFunctionToDataRange(False, True)
            c.SetScalarBarVisibility(view, True)
            pv.GetScalarBar(pv.GetColorTransferFunction(disk_field), view).Title = \
                "disks: " + legend_title(disk_field)
        else:
            pv.ColorBy(c, None)
            c.AmbientColor = c.DiffuseColor = [0.78, 0.66, 0.45]  # sand

    index = frames.index(shown)
    text = pv.Text(registrationName="legend")
    text.Text = ("%s\nt = %.4g s (frame %d of %d)\nprojectile outlined (body 0)%s"
                 % (os.path.abspath(run), shown.time, index, len(frames) - 1,
                    "; disks: circles of their radius" if disks else ""))
    t = pv.Show(text, view)
    t.WindowLocation = "Upper Left Corner"
    t.FontSize = 14

    pv.SetActiveView(view)
    pv.SetActiveSource(grains)
    view.ResetCamera()
    pv.Render(view)
    if screenshot:
        pv.SaveScreenshot(screenshot, view, ImageResolution=list(size))
    return view


def main(argv):
    a = parse_args(argv)
    try:
        if a.list:
            frames = read_collection(find_collection(a.run))
            print("\n".join(describe(frames, vtu_arrays(frames[0].fe))))
            return 0
        try:
            importlib.import_module("paraview.simple")
        except ImportError:
            print("show.py: paraview.simple not found: run it with ParaView's pvpython or pvbatch "
                  "(paraview.org; Debian's paraview package conflicts with libvtk9-dev), or use "
                  "--list", file=sys.stderr)
            return 2
        show(a.run, field=a.field, frame=a.frame, screenshot=a.screenshot, size=a.size,
             value_range=a.range, colormap=a.colormap, disk_field=a.disk_field)
        if a.screenshot:
            print("show.py: wrote %s" % a.screenshot)
        else:
            from paraview import simple as pv
            try:
                pv.Interact()  # pvpython: a window until q is pressed
            except RuntimeError:  # pvbatch has no window to interact with
                print("show.py: no interactive window here (pvbatch?): give --screenshot PNG",
                      file=sys.stderr)
                return 2
    except RunFilesError as e:
        print("show.py: %s" % e, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
