"""A stand-in for ParaView's `paraview.simple`, enough to run tools/paraview/show.py's show() where
ParaView is not installed (Debian's paraview conflicts with libvtk9-dev): it records the pipeline
show() builds and refuses a property or an enumeration value that ParaView 5.11 does not have (the
names and values below are those of 5.11's proxy definitions, e.g. Glyph in
VTKExtensions/FiltersGeneral/Resources/general_filters.xml). What ParaView then draws is not tested
here; tests/liggghts/vtk_files.py renders the same recipe with VTK.

    fake = fake_paraview.install()   # sys.modules["paraview"] and ["paraview.simple"]
    show.show(RUN_DIR, ...)
    fake.created                     # every proxy made, in order
"""
import sys
import types

# Properties (Python names: the XML labels without spaces) and enumerations of ParaView 5.11.
PROPERTIES = {
    "PVDReader": {"FileName", "TimestepValues", "CellArrays", "PointArrays", "ColumnArrays"},
    "ExtractBlock": {"Input", "Assembly", "Selectors"},
    "Threshold": {"Input", "Scalars", "LowerThreshold", "UpperThreshold", "ThresholdMethod",
                  "AllScalars", "UseContinuousCellRange", "Invert"},
    "ExtractSurface": {"Input", "PieceInvariant", "NonlinearSubdivisionLevel", "FastMode",
                       "RemoveGhostInterfaces"},
    "FeatureEdges": {"Input", "BoundaryEdges", "FeatureEdges", "NonManifoldEdges", "ManifoldEdges",
                     "Coloring", "FeatureAngle"},
    "Glyph": {"Input", "GlyphType", "OrientationArray", "ScaleArray", "VectorScaleMode",
              "ComponentSelection", "ScaleFactor", "GlyphTransform", "GlyphMode",
              "MaximumNumberOfSamplePoints", "Seed", "Stride"},
    "2D Glyph": {"GlyphType", "Filled", "Center"},
    "Text": {"Text"},
    "RenderView": {"ViewSize", "InteractionMode", "OrientationAxesVisibility", "ViewTime",
                   "CameraPosition", "CameraFocalPoint", "CameraViewUp", "CameraParallelScale"},
    "GeometryRepresentation": {"Representation", "AmbientColor", "DiffuseColor", "LineWidth",
                               "Opacity", "ColorArrayName", "PointSize"},
    "TextSourceRepresentation": {"WindowLocation", "FontSize", "Color", "Bold", "Justification"},
    "PVLookupTable": {"AutomaticRescaleRangeMode", "RGBPoints", "ColorSpace"},
    "PiecewiseFunction": {"Points"},
    "ScalarBarWidgetRepresentation": {"Title", "ComponentTitle", "WindowLocation", "Orientation",
                                      "Visibility"},
    "AnimationScene": {"AnimationTime", "PlayMode"},
}
ENUMERATIONS = {
    ("Threshold", "ThresholdMethod"): {"Between", "Below Lower Threshold", "Above Upper Threshold"},
    ("Glyph", "GlyphType"): {"Arrow", "Cone", "Box", "Cylinder", "Line", "Sphere", "2D Glyph"},
    ("Glyph", "GlyphMode"): {"All Points", "Every Nth Point",
                             "Uniform Spatial Distribution (Bounds Based)",
                             "Uniform Spatial Distribution (Surface Sampling)",
                             "Uniform Spatial Distribution (Volume Sampling)"},
    ("2D Glyph", "GlyphType"): {"Vertex", "Dash", "Cross", "ThickCross", "Triangle", "Square",
                                "Circle", "Diamond", "Arrow", "ThickArrow", "HookedArrow",
                                "EdgeArrow"},
    ("RenderView", "InteractionMode"): {"3D", "2D", "Selection"},
    ("TextSourceRepresentation", "WindowLocation"): {
        "Any Location", "Lower Left Corner", "Lower Right Corner", "Lower Center",
        "Upper Left Corner", "Upper Right Corner", "Upper Center"},
    ("PVLookupTable", "AutomaticRescaleRangeMode"): {
        "Never", "Grow and update on 'Apply'", "Grow and update every timestep",
        "Update on 'Apply'", "Clamp and update every timestep"},
}
# An array's association in Glyph's and Threshold's array properties.
ASSOCIATIONS = {"POINTS", "CELLS"}


class Proxy:
    """A proxy of `kind` that takes only 5.11's properties of that kind, and records them."""

    def __init__(self, fake, kind, **properties):
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "properties", {})
        object.__setattr__(self, "calls", [])
        fake.created.append(self)
        if kind == "Glyph":  # its glyph source: a proxy of its own, chosen by GlyphType's label
            self.properties["GlyphType"] = None
        for name, value in properties.items():
            setattr(self, name, value)

    def __setattr__(self, name, value):
        if name not in PROPERTIES[self.kind]:
            raise AttributeError("ParaView 5.11's %s has no property %s" % (self.kind, name))
        allowed = ENUMERATIONS.get((self.kind, name))
        if allowed is not None and value not in allowed:
            raise ValueError("%s.%s = %r: ParaView 5.11 allows %s"
                             % (self.kind, name, value, sorted(allowed)))
        if name in ("Scalars", "ScaleArray", "OrientationArray") and \
                (len(value) != 2 or value[0] not in ASSOCIATIONS):
            raise ValueError("%s.%s = %r: [association, array name]" % (self.kind, name, value))
        if self.kind == "Glyph" and name == "GlyphType":  # 2D Glyph's own properties
            value = Proxy(Fake.current, "2D Glyph") if value == "2D Glyph" else value
        self.properties[name] = value

    def __getattr__(self, name):
        properties = object.__getattribute__(self, "properties")
        if name in properties:
            return properties[name]
        raise AttributeError("%s: %s not set (or not a property of ParaView 5.11's)"
                             % (object.__getattribute__(self, "kind"), name))

    # Methods of sources, representations and transfer functions that show() calls.
    def record(self, name, *args):
        self.calls.append((name,) + args)

    def UpdatePipeline(self, time=None):
        self.record("UpdatePipeline", time)

    @property
    def CellData(self):
        return _ArrayInformation()

    @property
    def PointData(self):
        return _ArrayInformation()

    def SetRepresentationType(self, name):
        self.record("SetRepresentationType", name)

    def RescaleTransferFunctionToDataRange(self, extend=False, force=True):
        self.record("RescaleTransferFunctionToDataRange", extend, force)

    def SetScalarBarVisibility(self, view, visible):
        self.record("SetScalarBarVisibility", visible)

    def RescaleTransferFunction(self, low, high):
        if not high > low:
            raise ValueError("RescaleTransferFunction(%r, %r): an empty range" % (low, high))
        self.record("RescaleTransferFunction", low, high)

    def ApplyPreset(self, name, rescale=True):
        self.record("ApplyPreset", name, rescale)

    def UpdateAnimationUsingDataTimeSteps(self):
        self.record("UpdateAnimationUsingDataTimeSteps")

    def ResetCamera(self):
        self.record("ResetCamera")


class _ArrayInformation:
    """source.CellData[name].GetRange(component): a range of (0, 1)."""

    def __getitem__(self, name):
        return self

    def GetRange(self, component=0):
        return (0.0, 1.0)


class Fake:
    """The paraview.simple module's functions that show() uses."""
    current = None

    def __init__(self, version=(5, 11)):
        Fake.current = self
        self.version = version
        self.created = []       # every proxy, in order
        self.shown = []         # (source, representation)
        self.colored = []       # (representation, value of ColorBy)
        self.screenshots = []   # (file name, ImageResolution)
        self.view = None
        self.luts = {}

    def module(self):
        m = types.ModuleType("paraview.simple")
        for name in ("GetParaViewVersion", "GetActiveViewOrCreate", "PVDReader", "ExtractBlock",
                     "Threshold", "ExtractSurface", "FeatureEdges", "Glyph", "Text", "Show",
                     "ColorBy", "GetColorTransferFunction", "GetOpacityTransferFunction",
                     "GetScalarBar", "GetAnimationScene", "SetActiveView", "SetActiveSource",
                     "Render", "SaveScreenshot", "Interact"):
            setattr(m, name, getattr(self, name))
        return m

    def GetParaViewVersion(self):
        return types.SimpleNamespace(major=self.version[0], minor=self.version[1])

    def GetActiveViewOrCreate(self, kind):
        assert kind == "RenderView", kind
        if self.view is None:
            self.view = Proxy(self, "RenderView")
        return self.view

    def _source(kind):
        def make(self, registrationName=None, **properties):
            return Proxy(self, kind, **properties)
        return make
    PVDReader = _source("PVDReader")
    ExtractBlock = _source("ExtractBlock")
    Threshold = _source("Threshold")
    ExtractSurface = _source("ExtractSurface")
    FeatureEdges = _source("FeatureEdges")
    Glyph = _source("Glyph")
    Text = _source("Text")

    def Show(self, source, view):
        assert view is self.view, "Show in another view"
        kind = "TextSourceRepresentation" if source.kind == "Text" else "GeometryRepresentation"
        representation = Proxy(self, kind)
        object.__setattr__(representation, "source", source)
        self.shown.append((source, representation))
        return representation

    def ColorBy(self, representation, value):
        if value is not None and (value[0] not in ASSOCIATIONS or len(value) not in (2, 3)):
            raise ValueError("ColorBy(%r)" % (value,))
        self.colored.append((representation, value))

    def GetColorTransferFunction(self, name):
        return self.luts.setdefault(name, Proxy(self, "PVLookupTable"))

    def GetOpacityTransferFunction(self, name):
        return Proxy(self, "PiecewiseFunction")

    def GetScalarBar(self, lut, view):
        return Proxy(self, "ScalarBarWidgetRepresentation")

    def GetAnimationScene(self):
        return Proxy(self, "AnimationScene")

    def SetActiveView(self, view):
        pass

    def SetActiveSource(self, source):
        pass

    def Render(self, view=None):
        return view

    def SaveScreenshot(self, filename, view=None, ImageResolution=None):
        self.screenshots.append((filename, ImageResolution))

    def Interact(self, view=None):
        raise RuntimeError("Configuration doesn't support interaction.")

    def of_kind(self, kind):
        return [p for p in self.created if p.kind == kind]


def install(version=(5, 11)):
    """A fresh stand-in as the modules paraview and paraview.simple; returns it."""
    fake = Fake(version)
    simple = fake.module()
    package = types.ModuleType("paraview")
    package.simple = simple
    sys.modules["paraview"] = package
    sys.modules["paraview.simple"] = simple
    return fake
