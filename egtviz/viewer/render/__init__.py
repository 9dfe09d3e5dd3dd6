"""Rendering to SVG without viser: image-plane panels, plots, servo images, layout, figure and PNG export."""
