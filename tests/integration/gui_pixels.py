"""Reads a Swing window's screenshot without OCR, for lcm_spy_screenshot.sh (a helper, not a test).

Java under Xvfb draws lcm-spy without anti-aliasing: text is one dark grey (51), the table grid
one mid grey (135), backgrounds light (238, 255). So, from the pixels alone:

  table PNG  the channel table: its column edges (vertical grid lines through the whole body) and
             rows (cells between horizontal grid lines, the header left out); for each row the
             ink width of its Channel cell and of its Type cell, and where to click it. Prints JSON.
  lines PNG  the text lines of a decoder window (runs of pixel rows holding dark text), the
             scroll bar left out. Prints the count.
"""

import json
import subprocess
import sys

import numpy

TEXT_MAX = 100   # darker than this is text (51); the grid is 135
GRID = 135


def load(path):
    """The PNG as a grey-level array (rows, columns), through ImageMagick's PGM."""
    raw = subprocess.run(["convert", path, "-colorspace", "Gray", "-depth", "8", "pgm:-"], stdout=subprocess.PIPE,
                         check=True).stdout
    magic, size, maxval, data = raw.split(b"\n", 3)
    if magic != b"P5" or maxval != b"255":
        raise SystemExit("%s: unexpected PGM header %r %r" % (path, magic, maxval))
    w, h = map(int, size.split())
    return numpy.frombuffer(data, dtype=numpy.uint8)[:w * h].reshape(h, w)


def ink_extent(cell):
    """Width in pixels from the first to the last column holding text, 0 when none."""
    cols = numpy.nonzero((cell < TEXT_MAX).any(axis=0))[0]
    return int(cols[-1] - cols[0] + 1) if len(cols) else 0


def table(path):
    a = load(path)
    grid = a == GRID
    h, w = a.shape
    rows_h = [y for y in range(h) if grid[y].mean() > 0.9]          # horizontal grid lines
    # The header and the rows are cells one text line high, one under the other; the empty area
    # below the last row (and the Clear button under it) ends them.
    cells = []
    for t, b in zip(rows_h, rows_h[1:]):
        if b - t <= 4:
            continue
        if b - t >= 40:
            if cells:
                break
            continue
        cells.append((t, b))
    if len(cells) < 2:
        return {"error": "no table grid found", "rows": []}
    header, body = cells[0], cells[1:]
    top, bottom = body[0][0], body[-1][1]
    edges = [x for x in range(w) if grid[top:bottom, x].mean() > 0.95]  # vertical grid lines
    columns = [(l, r) for l, r in zip(edges, edges[1:]) if r - l > 4]
    if len(columns) < 2:
        return {"error": "fewer than 2 table columns", "rows": []}
    (cl, cr), (tl, tr) = columns[0], columns[1]
    rows = []
    for t, b in body:
        channel = ink_extent(a[t + 1:b, cl + 1:cr])
        if channel == 0:
            continue  # an empty row below the last channel
        kind = ink_extent(a[t + 1:b, tl + 1:tr])
        rows.append({"y": (t + b) // 2, "x": (cl + cr) // 2, "channel_ink": channel, "type_ink": kind,
                     "ratio": round(kind / channel, 3)})
    return {"columns": columns, "header": header, "rows": rows}


def lines(path):
    a = load(path)
    h, w = a.shape
    dark = (a[2:h - 2, 4:max(w - 24, 5)] < TEXT_MAX).any(axis=1)
    n, prev = 0, False
    for d in dark:
        n += 1 if d and not prev else 0
        prev = d
    return n


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("table", "lines"):
        raise SystemExit("usage: gui_pixels.py table|lines PNG")
    if sys.argv[1] == "table":
        print(json.dumps(table(sys.argv[2])))
    else:
        print(lines(sys.argv[2]))
