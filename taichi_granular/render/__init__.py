"""Headless rendering of particle frames to PNG (Taichi rasteriser, imageio output)."""
