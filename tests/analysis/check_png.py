#!/usr/bin/python3
"""Fails (exit 1) unless every PNG given is a real figure, not a blank page.

A figure passes when it is at least 300 x 200 pixels, has at least 16
distinct colours, at least 3 % of its pixels differ from the most common
(background) colour, and at least 0.5 % are strongly coloured (channel spread
over 60 of 255) -- every curvlab figure draws its data in colour, while axes,
grid lines and text are grey, so an empty panel fails. Read with matplotlib's PNG reader (independent of the R
device that wrote it).
"""
import sys

import numpy as np
from matplotlib import image


def verdict(path):
    try:
        img = image.imread(path)
    except (OSError, ValueError, SyntaxError) as e:
        return f"unreadable ({e})"
    h, w = img.shape[:2]
    pixels = (np.round(img.reshape(h * w, -1) * 255)).astype(np.uint8)
    colours, counts = np.unique(pixels, axis=0, return_counts=True)
    inked = 1.0 - counts.max() / counts.sum()
    if w < 300 or h < 200:
        return f"too small ({w}x{h})"
    if len(colours) < 16:
        return f"only {len(colours)} colours"
    if inked < 0.03:
        return f"only {100 * inked:.1f}% of pixels differ from the background"
    rgb = pixels[:, :3].astype(int)
    coloured = np.mean(rgb.max(axis=1) - rgb.min(axis=1) > 60)
    if coloured < 0.005:
        return f"only {100 * coloured:.2f}% of pixels are coloured (no data drawn?)"
    return None


def main():
    bad = 0
    for path in sys.argv[1:]:
        problem = verdict(path)
        print(f"{'FAIL' if problem else 'ok  '} {path}{': ' + problem if problem else ''}")
        bad += problem is not None
    sys.exit(1 if bad or len(sys.argv) < 2 else 0)


if __name__ == "__main__":
    main()
