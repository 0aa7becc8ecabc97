#!/usr/bin/python3
"""Checks an rviz screenshot of the detection demo (scripts/screenshot.sh): not blank, the
segmented cloud drawn (bright rainbow label colours), and object markers drawn: pixels of the
colours ObjectMarkers gives objects (hue from the golden-ratio sequence of the id, saturation
0.85, value 0.95, see src/ros/object_markers.cpp), blended at the box alpha over the rviz
background, for several distinct ids; the class legend (ns "legend" of ObjectMarkers: each
LiDAR class name drawn in its class colour) and vehicle boxes in the vehicle colour; each
legend colour readable on the background (WCAG contrast ratio >= 4.5). Exit status 0 when all
hold; prints the measurements.
  check_screenshot.py IMAGE.png [--alpha 0.45] [--background 30,30,34] [--min-ids 3]
"""
import argparse
import colorsys
import subprocess
import sys

import numpy as np


def load_rgb(path):
    """RGB uint8 array via ImageMagick (no PIL on a plain Debian)."""
    size = subprocess.check_output(['identify', '-format', '%w %h', path]).split()
    w, h = int(size[0]), int(size[1])
    raw = subprocess.check_output(['convert', path, '-depth', '8', 'rgb:-'])
    return np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)


def marker_colour(object_id, alpha, background):
    """The colour of object `object_id`'s box as drawn over `background` (0..255 floats)."""
    h = (object_id * 0.6180339887498949) % 1.0
    r, g, b = colorsys.hsv_to_rgb(h, 0.85, 0.95)
    return alpha * 255.0 * np.array([r, g, b]) + (1.0 - alpha) * np.asarray(background, float)


# ObjectMarkers' class colours of the LiDAR classifier's classes (src/ros/object_markers.cpp).
CLASS_COLOURS = {'vehicle': (40, 150, 255), 'pedestrian': (255, 70, 110),
                 'cyclist': (255, 210, 0), 'other_object': (0, 230, 200)}


def luminance(rgb):
    """WCAG relative luminance of an sRGB colour (0..255)."""
    lin = [c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4
           for c in (v / 255.0 for v in rgb)]
    return 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]


def main():
    p = argparse.ArgumentParser()
    p.add_argument('image')
    p.add_argument('--alpha', type=float, default=0.45)
    p.add_argument('--background', default='30,30,34')
    p.add_argument('--max-id', type=int, default=80)
    p.add_argument('--tolerance', type=float, default=14.0, help='RGB distance to a marker colour')
    p.add_argument('--min-pixels-per-id', type=int, default=40)
    p.add_argument('--min-ids', type=int, default=0,
                   help='boxes in id colours (unclassified objects: --classifier off)')
    p.add_argument('--min-legend-pixels', type=int, default=20,
                   help='pixels of each legend colour (the class names are drawn in it)')
    p.add_argument('--no-legend', action='store_true', help='skip the legend and class checks')
    args = p.parse_args()
    background = [float(v) for v in args.background.split(',')]

    img = load_rgb(args.image).astype(np.float32)
    pix = img.reshape(-1, 3)
    failures = []

    grey = pix.mean(axis=1)
    values, counts = np.unique(pix.astype(np.uint8), axis=0, return_counts=True)
    dominant = counts.max() / float(len(pix))
    print('image %dx%d: grey std %.1f, most common colour covers %.1f%%'
          % (img.shape[1], img.shape[0], grey.std(), 100 * dominant))
    if grey.std() < 5.0 or dominant > 0.97:
        failures.append('image is (nearly) blank')

    mx, mn = pix.max(axis=1), pix.min(axis=1)
    bright_saturated = int(np.count_nonzero((mx > 200) & (mx - mn > 120)))
    print('bright saturated (cloud label colours) pixels: %d' % bright_saturated)
    if bright_saturated < 500:
        failures.append('no coloured point cloud visible')

    matched = {}
    for object_id in range(1, args.max_id + 1):
        c = marker_colour(object_id, args.alpha, background)
        n = int(np.count_nonzero(np.linalg.norm(pix - c, axis=1) < args.tolerance))
        if n >= args.min_pixels_per_id:
            matched[object_id] = n
    print('object ids whose marker colour covers >= %d pixels: %d %s'
          % (args.min_pixels_per_id, len(matched), sorted(matched.items())[:12]))
    if len(matched) < args.min_ids:
        failures.append('object markers not visible (%d ids, need %d)'
                        % (len(matched), args.min_ids))

    if not args.no_legend:
        bg_lum = luminance(background)
        for name, rgb in CLASS_COLOURS.items():
            contrast = (luminance(rgb) + 0.05) / (bg_lum + 0.05)
            n = int(np.count_nonzero(np.linalg.norm(pix - np.array(rgb, float), axis=1) < 30.0))
            print('legend %-12s colour %s: %d pixels, contrast %.1f on the background'
                  % (name, rgb, n, contrast))
            if n < args.min_legend_pixels:
                failures.append('legend entry %s not visible' % name)
            if contrast < 4.5:
                failures.append('class colour of %s unreadable on the background (%.1f)'
                                % (name, contrast))
        box = args.alpha * np.array(CLASS_COLOURS['vehicle'], float) + \
            (1.0 - args.alpha) * np.asarray(background, float)
        n = int(np.count_nonzero(np.linalg.norm(pix - box, axis=1) < args.tolerance))
        print('vehicle box pixels: %d' % n)
        if n < args.min_pixels_per_id:
            failures.append('no vehicle box in the vehicle colour')

    for f in failures:
        print('FAIL: ' + f)
    print('screenshot check: %s' % ('FAILED' if failures else 'ok'))
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
