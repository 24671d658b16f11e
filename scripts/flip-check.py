#!/usr/bin/env python3
"""Compare dibench's FLIP (src/flip.rs) with NVIDIA's reference implementation.

Set-up (a virtual environment outside the repository):

    python3 -m venv /work/flip-venv
    /work/flip-venv/bin/pip install flip-evaluator numpy
    /work/flip-venv/bin/python scripts/flip-check.py

The script builds `examples/flip_pair.rs` (cargo build --release --example flip_pair; or
--bin PATH to use a built one), makes a few image pairs with numpy (deterministic seeds), runs
both implementations on each in LDR and HDR mode, and prints per case the largest per-pixel
|difference| of the maps and the relative difference of the means. It exits 1 if a case is
outside --tol-pixel (default 1e-3) or --tol-mean (relative, default 1e-3).

--exr REF.exr TEST.exr adds a pair of dibench renders (read through flip_pair's `convert`).
--constants prints the reference values for the committed-constant test in src/flip.rs.

Raw image files (flip_pair's format): little-endian u32 width, u32 height, then f32 RGB.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import flip_evaluator as flip

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def write_raw(path, img):
    img = np.ascontiguousarray(img, dtype="<f4")
    h, w, _ = img.shape
    with open(path, "wb") as f:
        f.write(np.array([w, h], dtype="<u4").tobytes())
        f.write(img.tobytes())


def read_raw(path, channels):
    with open(path, "rb") as f:
        data = f.read()
    w, h = np.frombuffer(data[:8], dtype="<u4")
    return np.frombuffer(data[8:], dtype="<f4").reshape(h, w, channels).astype(np.float32)  # a writable copy


def srgb_encode(lin):
    lin = np.clip(lin, 0.0, 1.0)
    return np.where(lin <= 0.0031308, lin * 12.92, 1.055 * lin ** (1 / 2.4) - 0.055).astype(np.float32)


# ------------------------------------------------------------------------------------------
# Image pairs: (name, reference linear HDR, test linear HDR). LDR mode uses the sRGB encoding
# of the clamped linear images.


def gradient_pair(rng, w=160, h=96):
    x = np.linspace(0.0, 1.0, w, dtype=np.float32)[None, :]
    y = np.linspace(0.0, 1.0, h, dtype=np.float32)[:, None]
    ref = np.stack([x * np.ones_like(y), y * np.ones_like(x), 0.5 * (x + y) * 0.8 + 0.1], axis=-1)
    test = ref + rng.normal(0.0, 0.04, ref.shape).astype(np.float32)
    return ref.astype(np.float32), np.clip(test, 0.0, None).astype(np.float32)


def cornell_like(w=128, h=128):
    """A diffusely shaded box: red left wall, green right wall, white rest, ceiling light."""
    img = np.zeros((h, w, 3), np.float32)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    u, v = (xs + 0.5) / w, (ys + 0.5) / h
    light = np.array([0.5, 0.02])
    d2 = (u - light[0]) ** 2 + (v - light[1]) ** 2 + 0.05
    shade = (0.12 / d2).astype(np.float32)
    white = np.array([0.73, 0.73, 0.73], np.float32)
    red = np.array([0.63, 0.065, 0.05], np.float32)
    green = np.array([0.14, 0.45, 0.091], np.float32)
    albedo = np.broadcast_to(white, (h, w, 3)).copy()
    albedo[u < 0.15] = red
    albedo[u > 0.85] = green
    img = albedo * shade[..., None]
    # Two boxes with soft shadows.
    for (x0, x1, y0, y1) in [(0.25, 0.45, 0.55, 0.9), (0.55, 0.75, 0.4, 0.9)]:
        inside = (u > x0) & (u < x1) & (v > y0) & (v < y1)
        img[inside] = white * shade[inside][:, None] * 0.6
        sh = (u > x0 - 0.05) & (u < x1 + 0.05) & (v > y1) & (v < y1 + 0.06)
        img[sh] *= 0.35
    # The emitter (radiance 12, as in scenes/cornell.toml).
    emit = (np.abs(u - 0.5) < 0.12) & (v < 0.03)
    img[emit] = 12.0
    return img.astype(np.float32)


def cornell_pair(rng, spp=4):
    ref = cornell_like()
    # Monte Carlo-like noise: the mean of spp exponential samples of the pixel's value.
    samples = rng.exponential(1.0, (spp,) + ref.shape).astype(np.float32)
    test = ref * samples.mean(axis=0)
    return ref, test.astype(np.float32)


def edge_pair(w=96, h=80):
    ys, xs = np.mgrid[0:h, 0:w]
    ref = np.zeros((h, w, 3), np.float32)
    ref[(xs // 12 + ys // 10) % 2 == 0] = [0.9, 0.8, 0.7]
    ref[(xs + ys) % 31 == 0] = [0.1, 0.3, 1.0]  # thin diagonal lines
    test = np.roll(ref, 1, axis=1)  # shifted right by one pixel
    return ref, test


def bright_pair(rng, w=64, h=48):
    ref = (rng.uniform(0.0, 2.0, (h, w, 3))).astype(np.float32)
    ref[10:14, 20:26] = 1e4
    test = ref.copy()
    test[11:15, 21:27] = 1e4
    test += rng.normal(0.0, 0.05, test.shape).astype(np.float32)
    return ref, np.clip(test, 0.0, None).astype(np.float32)


def mostly_black_pair(rng, w=64, h=48):
    """More than half of the reference black: median luminance 0, floored at f32 epsilon."""
    ref = np.zeros((h, w, 3), np.float32)
    ref[:, : w // 3] = rng.uniform(0.1, 3.0, (h, w // 3, 3))
    test = ref * rng.uniform(0.8, 1.2, ref.shape).astype(np.float32)
    return ref, test.astype(np.float32)


def tiny_pair():
    """The 16×16 pair of src/flip.rs's committed-constant tests (exact f32 arithmetic)."""
    ys, xs, cs = np.mgrid[0:16, 0:16, 0:3]
    ref = ((xs * 3 + ys * 5 + cs * 7) % 16).astype(np.float32) / np.float32(15)
    test = ((xs * 3 + ys * 5 + cs * 7 + (xs * ys) % 3) % 16).astype(np.float32) / np.float32(15)
    return ref.astype(np.float32), test.astype(np.float32)


def tiny_hdr(img):
    """HDR version: ×4 with an 'emitter' of 12 in a 3×2 block."""
    out = img * np.float32(4)
    out[2:4, 5:8] = 12.0
    return out.astype(np.float32)


# ------------------------------------------------------------------------------------------


def reference_flip(ref, test, mode, ppd):
    params = {} if ppd is None else {"ppd": float(ppd)}
    if mode == "ldr":
        m, mean, p = flip.evaluate(ref, test, "LDR", inputsRGB=True, applyMagma=False, parameters=params)
    else:
        m, mean, p = flip.evaluate(ref, test, "HDR", applyMagma=False, parameters=params)
    return np.asarray(m)[..., 0], mean, p


def dibench_flip(binary, tmp, ref, test, mode, ppd):
    rp, tp, op = (os.path.join(tmp, n) for n in ("ref.raw", "test.raw", "out.raw"))
    write_raw(rp, ref)
    write_raw(tp, test)
    args = [binary, mode, rp, tp, op] + ([] if ppd is None else [repr(float(ppd))])
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    fields = dict(kv.split("=") for kv in out.split())
    return read_raw(op, 1)[..., 0], fields


def build(args):
    if args.bin:
        return args.bin
    subprocess.run(["cargo", "build", "--release", "--example", "flip_pair"], cwd=REPO, check=True)
    return os.path.join(REPO, "target", "release", "examples", "flip_pair")


def read_exr(binary, tmp, path):
    out = os.path.join(tmp, os.path.basename(path) + ".raw")
    subprocess.run([binary, "convert", path, out], check=True)
    return read_raw(out, 3)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", help="a built flip_pair (default: build it with cargo)")
    ap.add_argument("--exr", nargs=2, action="append", default=[], metavar=("REF", "TEST"))
    ap.add_argument("--tol-pixel", type=float, default=1e-3)
    ap.add_argument("--tol-mean", type=float, default=1e-3)
    ap.add_argument("--constants", action="store_true")
    args = ap.parse_args()

    if args.constants:
        ref, test = tiny_pair()
        for mode, r, t in [("ldr", ref, test), ("hdr", tiny_hdr(ref), tiny_hdr(test))]:
            for ppd in [None, 30.0]:
                m, mean, p = reference_flip(r, t, mode, ppd)
                print(f"{mode} ppd={p['ppd']!r}: mean(f64)={m.astype(np.float64).mean()!r} "
                      f"reported={mean!r} params={p}")
                for (x, y) in [(0, 0), (5, 3), (15, 15), (7, 12)]:
                    print(f"    ({x}, {y}) = {float(m[y, x])!r}")
        return 0

    binary = build(args)
    rng = np.random.default_rng(18)
    cases = []
    cases.append(("gradient vs noisy", *gradient_pair(rng), None))
    cases.append(("cornell-like vs 4 spp", *cornell_pair(rng), None))
    cases.append(("edges vs shifted 1 px", *edge_pair(), None))
    g = gradient_pair(rng)[1]
    cases.append(("identical", g, g.copy(), None))
    cases.append(("cornell-like, ppd 30", *cornell_pair(rng, 16), 30.0))
    cases.append(("edges, ppd 110", *edge_pair(61, 47), 110.0))
    cases.append(("bright 1e4 spots", *bright_pair(rng), None))
    cases.append(("tiny 16x16", *tiny_pair(), None))
    cases.append(("median-0 reference", *mostly_black_pair(rng), None))
    with tempfile.TemporaryDirectory() as tmp:
        for r, t in args.exr:
            label = os.path.basename(os.path.dirname(os.path.dirname(os.path.abspath(t))))  # results/<scene>/...
            cases.append((f"render {label}", read_exr(binary, tmp, r), read_exr(binary, tmp, t), None))

        failed = False
        print(f"{'case':28} {'mode':4} {'size':>8} {'ref mean':>12} {'dibench mean':>12} "
              f"{'mean rel':>9} {'max |px|':>9}  exposures (ref | dibench)")
        for name, ref, test, ppd in cases:
            for mode in ["ldr", "hdr"]:
                r, t = (srgb_encode(ref), srgb_encode(test)) if mode == "ldr" else (ref, test)
                rm, rmean, rp = reference_flip(r, t, mode, ppd)
                dm, fields = dibench_flip(binary, tmp, r, t, mode, ppd)
                ref_mean = float(rm.astype(np.float64).mean())
                our_mean = float(fields["mean"])
                rel = abs(our_mean - ref_mean) / ref_mean if ref_mean > 0 else abs(our_mean)
                px = float(np.max(np.abs(dm.astype(np.float64) - rm)))
                bad = rel > args.tol_mean or px > args.tol_pixel or not np.all(np.isfinite(dm))
                if name == "identical" and (np.any(dm != 0) or np.any(rm != 0)):
                    bad = True
                failed |= bad
                exp = ""
                if mode == "hdr":
                    exp = (f"{rp['startExposure']:.4f}..{rp['stopExposure']:.4f} x{rp['numExposures']} | "
                           f"{float(fields['start']):.4f}..{float(fields['stop']):.4f} x{fields['count']}")
                print(f"{name:28} {mode:4} {ref.shape[1]:>4}x{ref.shape[0]:<3} {ref_mean:12.7f} {our_mean:12.7f} "
                      f"{rel:9.2e} {px:9.2e}  {exp}{'  FAIL' if bad else ''}")

    print("FAIL" if failed else "all cases within tolerance")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
