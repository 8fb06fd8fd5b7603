#!/usr/bin/python3
"""Compares what the Windows build wrote with what the Linux build wrote.

  compare.py json LINUX WINDOWS [--tol 1e-12] [--ignore KEY,...]  numbers equal to a relative 1e-12
  compare.py csv LINUX WINDOWS --ignore COL,COL,...  cells equal (numbers to 1e-12) but in the named columns
  compare.py rows FIRST SECOND [--only COL=V,...]    every (such) row of FIRST is in SECOND
  compare.py png LINUX WINDOWS [--tol 0]             pixels (RGBA) differ by at most tol

Exit 0 when equal, 1 with the first differences on stderr.
"""
import argparse
import csv
import io
import json
import math
import struct
import sys
import zlib


def fail(lines):
    for line in lines[:20]:
        print(line, file=sys.stderr)
    if len(lines) > 20:
        print(f"... and {len(lines) - 20} more", file=sys.stderr)
    return 1


def json_diffs(a, b, tol, where="$", ignore=frozenset()):
    if isinstance(a, bool) or isinstance(b, bool):
        return [] if a == b else [f"{where}: {a!r} != {b!r}"]
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if a == b or (math.isnan(a) and math.isnan(b)):
            return []
        scale = max(1.0, abs(a), abs(b))
        return [] if abs(a - b) <= tol * scale else [f"{where}: {a!r} != {b!r}"]
    if type(a) is not type(b):
        return [f"{where}: {a!r} != {b!r}"]
    if isinstance(a, dict):
        out = [f"{where}: key {k!r} only in {'Linux' if k in a else 'Windows'}" for k in sorted(set(a) ^ set(b))]
        for k in a:
            if k in b and k not in ignore:
                out += json_diffs(a[k], b[k], tol, f"{where}.{k}", ignore)
        return out
    if isinstance(a, list):
        if len(a) != len(b):
            return [f"{where}: {len(a)} items != {len(b)} items"]
        out = []
        for i, (x, y) in enumerate(zip(a, b)):
            out += json_diffs(x, y, tol, f"{where}[{i}]", ignore)
        return out
    return [] if a == b else [f"{where}: {a!r} != {b!r}"]


def read_text(path):
    with open(path, "rb") as f:
        data = f.read()
    return data.decode("utf-8")


def compare_json(args):
    a, b = json.loads(read_text(args.linux)), json.loads(read_text(args.windows))
    diffs = json_diffs(a, b, args.tol, ignore=frozenset(filter(None, (args.ignore or "").split(","))))
    return fail(diffs) if diffs else 0


def numbers_close(x, y, tol):
    """Both cells numbers equal to a relative tol (libm rounding differs by
    platform in the last bit)."""
    try:
        a, b = float(x), float(y)
    except ValueError:
        return False
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))


def compare_csv(args):
    ignore = set(filter(None, (args.ignore or "").split(",")))
    with open(args.linux, newline="") as f:
        la = list(csv.reader(f))
    with open(args.windows, newline="") as f:
        lb = list(csv.reader(f))
    if not la or la[0] != lb[0]:
        return fail([f"header differs:\n  {la[:1]}\n  {lb[:1]}"])
    if len(la) != len(lb):
        return fail([f"{len(la) - 1} rows != {len(lb) - 1} rows"])
    header = la[0]
    missing = ignore - set(header)
    if missing:
        return fail([f"no column named {', '.join(sorted(missing))}"])
    out = []
    for r, (x, y) in enumerate(zip(la[1:], lb[1:]), start=2):
        for c, name in enumerate(header):
            if name not in ignore and x[c] != y[c] and not numbers_close(x[c], y[c], args.tol):
                out.append(f"row {r} {name}: {x[c]!r} != {y[c]!r}")
    return fail(out) if out else 0


def compare_rows(args):
    """Every row of the first CSV appears, the same, in the second."""
    ignore = set(filter(None, (args.ignore or "").split(",")))
    with open(args.linux, newline="") as f:
        la = list(csv.reader(f))
    with open(args.windows, newline="") as f:
        lb = list(csv.reader(f))
    if la[0] != lb[0]:
        return fail(["headers differ"])
    keep = [c for c, name in enumerate(la[0]) if name not in ignore]
    only = {}
    for cond in filter(None, (args.only or "").split(",")):
        name, value = cond.split("=", 1)
        only[la[0].index(name)] = value
    later = {tuple(r[c] for c in keep) for r in lb[1:]}
    lost = [f"row {i}: {r}" for i, r in enumerate(la[1:], start=2)
            if all(r[c] == v for c, v in only.items()) and tuple(r[c] for c in keep) not in later]
    return fail(["rows missing or changed in " + args.windows] + lost) if lost else 0


def read_png(path):
    """RGBA8 pixels of a non-interlaced 8-bit RGBA PNG (what curvlab writes)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    pos, idat, width = 8, b"", None
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if (depth, color, interlace) != (8, 6, 0):
                raise ValueError(f"{path}: not 8-bit RGBA without interlace")
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride, bpp = zlib.decompress(idat), width * 4, 4
    rows, prev, i = [], bytearray(stride), 0
    for _ in range(height):
        ftype, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if ftype == 1:
                line[x] = (line[x] + a) & 255
            elif ftype == 2:
                line[x] = (line[x] + b) & 255
            elif ftype == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, b"".join(rows)


def compare_png(args):
    wa, ha, pa = read_png(args.linux)
    wb, hb, pb = read_png(args.windows)
    if (wa, ha) != (wb, hb):
        return fail([f"size {wa}x{ha} != {wb}x{hb}"])
    worst = max((abs(x - y) for x, y in zip(pa, pb)), default=0)
    differing = sum(1 for k in range(0, len(pa), 4) if pa[k:k + 4] != pb[k:k + 4])
    print(f"{args.windows}: {differing} of {wa * ha} pixels differ, by at most {worst}")
    return 0 if worst <= args.tol else fail([f"pixels differ by up to {worst} (tolerance {args.tol})"])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("kind", choices=["json", "csv", "rows", "png"])
    p.add_argument("linux")
    p.add_argument("windows")
    p.add_argument("--tol", type=float)
    p.add_argument("--ignore")
    p.add_argument("--only", help="rows: only the rows of FIRST with COL=VALUE")
    args = p.parse_args()
    if args.tol is None:
        args.tol = 0 if args.kind == "png" else 1e-12
    return {"json": compare_json, "csv": compare_csv, "rows": compare_rows, "png": compare_png}[args.kind](args)


if __name__ == "__main__":
    sys.exit(main())
