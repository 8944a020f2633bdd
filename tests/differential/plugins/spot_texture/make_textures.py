#!/usr/bin/env python3
"""The light textures of spot_texture and projector: a checker whose four quadrants have
different colours, so that u or v mirrored, the image turned or the texture ignored moves
colour between blocks of the rendered floor."""

import os

from PIL import Image

QUADRANTS = [[(255, 60, 40), (60, 230, 60)], [(50, 90, 255), (255, 255, 255)]]


def quadrant_checker(width, height, cell, path):
    img = Image.new("RGB", (width, height))
    for y in range(height):
        for x in range(width):
            colour = QUADRANTS[2 * y // height][2 * x // width]
            dark = ((x // cell) + (y // cell)) % 2
            img.putpixel((x, y), tuple(c // 6 for c in colour) if dark else colour)
    img.save(path)


here = os.path.dirname(os.path.abspath(__file__))
quadrant_checker(32, 32, 4, os.path.join(here, "quadrants.png"))
quadrant_checker(32, 24, 4, os.path.join(here, "..", "projector", "quadrants_wide.png"))
