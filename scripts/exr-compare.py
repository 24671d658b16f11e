#!/usr/bin/env python3
"""Compare two dibench reference manifests' EXR files, value by value (standard library only).

    scripts/exr-compare.py A.json B.json [--rel 1e-5]

A and B are reference manifests (`<out>/<scene>/reference/<integrand>.json`). For the image and
the variance file of each, both EXRs are decoded (scan-line f32/f16, NONE/ZIPS/ZIP compression:
what `dibench` writes) and every channel value compared: the largest relative difference
|a - b| / scale must stay below --rel (the f32 roundoff a different summation order may cause),
where scale is max(|a|, |b|) for the image. For the variance it is max(|a|, |b|, (1e-7 m)²) with
m the pixel's value in A's image: a standard error below 1e-7 of the pixel, the image's own f32
resolution, counts as zero. (Pixels of constant radiance, such as an emitter seen directly, have
zero variance; Welford's update in one process leaves f64 roundoff there, ~1e-34, while Chan's
merge of the shards may give exactly 0.) As a check of this reader, the mean of each variance
EXR must match the manifest's noise_floor_rmse squared; and the two manifests must agree on
scene, integrand, size, spp and seed. Prints one line per file; exits 1 on any
mismatch, 2 on bad input.
"""

import itertools
import json
import math
import os
import struct
import sys
import zlib

LINES_PER_BLOCK = {0: 1, 2: 1, 3: 16}  # NONE, ZIPS, ZIP


def fail(msg):
    print(f"exr-compare: {msg}", file=sys.stderr)
    sys.exit(2)


def read_exr(path):
    """(width, height, {channel: [values row-major]}) of a scan-line EXR."""
    data = open(path, "rb").read()
    if data[:4] != b"\x76\x2f\x31\x01":
        fail(f"{path}: not an EXR file")
    if data[5] & 0x1E:  # tiled, long names, deep or multipart
        fail(f"{path}: only single-part scan-line EXRs are supported")
    pos, attrs = 8, {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        tend = data.index(b"\0", end + 1)
        size = struct.unpack_from("<i", data, tend + 1)[0]
        attrs[name] = data[tend + 5 : tend + 5 + size]
        pos = tend + 5 + size
    pos += 1
    channels, cpos, cl = [], 0, attrs["channels"]
    while cl[cpos] != 0:
        end = cl.index(b"\0", cpos)
        ptype = struct.unpack_from("<i", cl, end + 1)[0]
        xs, ys = struct.unpack_from("<ii", cl, end + 9)
        if (xs, ys) != (1, 1):
            fail(f"{path}: subsampled channels are not supported")
        channels.append((cl[cpos:end].decode(), ptype))
        cpos = end + 17
    compression = attrs["compression"][0]
    if compression not in LINES_PER_BLOCK:
        fail(f"{path}: compression {compression} is not supported")
    xmin, ymin, xmax, ymax = struct.unpack("<iiii", attrs["dataWindow"])
    width, height = xmax - xmin + 1, ymax - ymin + 1
    lines = LINES_PER_BLOCK[compression]
    chunks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{chunks}Q", data, pos)
    fmt = {1: ("e", 2), 2: ("f", 4)}
    for _, t in channels:
        if t not in fmt:
            fail(f"{path}: pixel type {t} is not supported")
    line_bytes = sum(fmt[t][1] for _, t in channels) * width
    values = {c: [0.0] * (width * height) for c, _ in channels}
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        row0 = y - ymin
        n = min(lines, height - row0)
        raw = data[off + 8 : off + 8 + size]
        if size < n * line_bytes:
            t = zlib.decompress(raw)
            t = bytes(itertools.accumulate(t, lambda a, b: (a + b - 128) & 0xFF))
            half = (len(t) + 1) // 2
            out = bytearray(len(t))
            out[0::2] = t[:half]
            out[1::2] = t[half:]
            raw = bytes(out)
        if len(raw) != n * line_bytes:
            fail(f"{path}: block at line {y} has {len(raw)} bytes, expected {n * line_bytes}")
        p = 0
        for r in range(n):
            for c, t in channels:
                code, nbytes = fmt[t]
                row = struct.unpack_from(f"<{width}{code}", raw, p)
                base = (row0 + r) * width
                values[c][base : base + width] = row
                p += nbytes * width
    return width, height, values


def stored(manifest, role):
    meta = json.load(open(manifest))
    f = meta.get("files", {}).get(role)
    if not f:
        fail(f"{manifest}: no {role} file listed")
    return os.path.join(os.path.dirname(manifest), f["name"]), meta


def main():
    args = sys.argv[1:]
    rel = 1e-5
    if "--rel" in args:
        i = args.index("--rel")
        rel = float(args[i + 1])
        del args[i : i + 2]
    if len(args) != 2:
        fail("usage: exr-compare.py A.json B.json [--rel 1e-5]")
    bad = False
    image = None
    for role in ("image", "variance"):
        (pa, ma), (pb, mb) = stored(args[0], role), stored(args[1], role)
        wa, ha, va = read_exr(pa)
        wb, hb, vb = read_exr(pb)
        if (wa, ha, sorted(va)) != (wb, hb, sorted(vb)):
            print(f"FAIL {role}: {wa}x{ha} {sorted(va)} vs {wb}x{hb} {sorted(vb)}")
            bad = True
            continue
        if role == "image":
            image = va
        elif image is None or sorted(image) != sorted(va) or len(image[next(iter(va))]) != wa * ha:
            fail(f"{pa}: the variance does not match the image's size and channels")
        worst, differing, count = 0.0, 0, 0
        for c in va:
            for i, (x, y) in enumerate(zip(va[c], vb[c])):
                count += 1
                if not (math.isfinite(x) and math.isfinite(y)):
                    worst = math.inf
                elif x != y:
                    differing += 1
                    scale = max(abs(x), abs(y), 1e-30)
                    if role == "variance":
                        scale = max(scale, (1e-7 * image[c][i]) ** 2)
                    worst = max(worst, abs(x - y) / scale)
        if role == "variance":
            for m, v in ((ma, va), (mb, vb)):
                floor = m.get("noise_floor_rmse")
                mean = sum(sum(ch) for ch in v.values()) / count
                if floor is None or not math.isclose(mean, floor * floor, rel_tol=1e-4):
                    print(f"FAIL reader check: mean variance {mean} vs noise floor² {floor}²")
                    bad = True
        if role == "image":
            for key in ("scene", "integrand", "width", "height", "spp", "seed"):
                if ma.get(key) != mb.get(key):
                    print(f"FAIL metadata: {key} is {ma.get(key)!r} vs {mb.get(key)!r}")
                    bad = True
        ok = worst < rel
        bad |= not ok
        print(
            f"{'ok' if ok else 'FAIL'} {role}: {wa}x{ha}, {differing} of {count} values differ, "
            f"largest relative difference {worst:.3g} (bound {rel:g})"
        )
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
