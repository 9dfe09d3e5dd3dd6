"""egtviz: interactive multiple-view geometry in the browser, after the Epipolar Geometry Toolbox."""

__version__ = "0.1.0"
