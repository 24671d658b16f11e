#!/usr/bin/env python3
"""Samples/s of dibench against Mitsuba 3 (`llvm_ad_rgb`, `direct`), single thread, same estimator.

Setup (once):
    python3 -m venv /work/mitsuba-venv && /work/mitsuba-venv/bin/pip install mitsuba numpy
    apt-get install -y libllvm19        # Dr.Jit's LLVM backend
    export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1   # the default here
Run (from the repository root, with the venv's python):
    /work/mitsuba-venv/bin/python scripts/bench-vs-mitsuba.py --dibench target/release/dibench
  add `--baseline OTHER_BINARY` to time a second build in the same rounds (before/after a change).

Each scene's TOML is translated into a Mitsuba scene dict:
  camera   `perspective`, fov = fov_y_deg, fov_axis='y', to_world = look_at(eye, look_at, up);
           `hdrfilm` (rgb) W×H, `box` rfilter, `independent` sampler.
  material diffuse albedo -> `twosided` `diffuse` (dibench reflects on both sides); other
           types are refused.
  quad     an OBJ of triangles (c, c+u, c+u+v), (c, c+u+v, c+v): Mitsuba's area emitter emits on
           the side of the face normal, i.e. of edge_u × edge_v, as dibench's quads.
  mesh     `obj`, face_normals=True (dibench's flat geometric normals), to_world = T·R_y·S.
  sphere   `sphere`; Mitsuba's emits outward only (dibench's both ways: same for points outside).
  lights   point (intensity = power/4π), directional (irradiance, direction of travel),
           linear_spot_light -> `spot` (linear in angle: beam_width = falloff_start_deg,
           cutoff_angle = cone_angle_deg); dibench's smoothstep `spot_light` has no Mitsuba twin
           and is refused. Environment file -> `envmap`, to_world = R_y(rotate_y_deg − 90°)
           (Mitsuba's u = atan2(x, −z)/2π, dibench's atan2(z, x)/2π; Mitsuba interpolates
           texels bilinearly, dibench's are piecewise constant); constant -> `constant`.
Estimators: `light` (one light sample by area) <-> `direct` emitter_samples=1, bsdf_samples=0;
`mis-power` <-> emitter_samples=1, bsdf_samples=1 (power heuristic on both sides), run as
dibench's `mis-power-area` where it applies (quads and mesh triangles by area, as Mitsuba samples
them), else `mis-power` (spheres: the cone on both sides). With an environment,
dibench's env-latlong-hier / mis-env-latlong-hier (Mitsuba's envmap warps hierarchically).
Mitsuba picks a light uniformly, dibench by power: the same for the one-light scenes here.

Timing: round r renders each scene with Mitsuba (JIT-compiled beforehand; one untimed render,
as the first after another scene's runs up to 2× slower, then mi.render(spp=N, seed=r) + numpy)
and then with dibench (`compare --threads 1 --time T --reference-spp 16`; samples/s from the
last checkpoint of results.csv). Everything written (OBJs, dibench runs, Dr.Jit's kernel cache
via HOME, the CSV) stays under --out.
"""
import argparse
import csv
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

LLVM_DEFAULT = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
ESTIMATORS = {"light": (1, 0), "mis-power": (1, 1)}  # (emitter_samples, bsdf_samples)


def applies(exe, scene, strategy):
    """Whether `dibench strategies SCENE` lists `strategy` as applying."""
    listing = subprocess.run([exe, "strategies", scene], capture_output=True, text=True, check=True).stdout
    return any(line.split()[:1] == [strategy] and line.rstrip().endswith("[applies]")
               for line in listing.splitlines())


def import_mitsuba(out):
    """Import Mitsuba and select the LLVM variant, or exit saying what is missing."""
    lib = os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM_DEFAULT)
    if not Path(lib).is_file():
        sys.exit(f"LLVM library {lib} not found: apt-get install libllvm19, or set DRJIT_LIBLLVM_PATH")
    os.environ["HOME"] = str(out)  # Dr.Jit caches kernels in ~/.drjit: keep it under --out
    try:
        import drjit as dr
        import mitsuba as mi
        mi.set_variant("llvm_ad_rgb")
    except (ImportError, AttributeError, RuntimeError) as e:
        sys.exit(f"mitsuba (llvm_ad_rgb) unavailable: {e}\n"
                 "use a venv with `pip install mitsuba numpy` (see this script's docstring)")
    return mi, dr


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def bsdf(mat):
    if mat.get("type", "diffuse") != "diffuse" or "specular" in mat or "exponent" in mat:
        raise ValueError(f"material {mat['name']!r} is not diffuse: no exact Mitsuba twin mapped")
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb(mat.get("albedo", [0, 0, 0]))}}


def area(shape, d):
    if "emission" in d:
        shape["emitter"] = {"type": "area", "radiance": rgb(d["emission"])}
    return shape


def quad_obj(q, path):
    c, u, v = (q[k] for k in ("corner", "edge_u", "edge_v"))
    pts = [[c[i] + a * u[i] + b * v[i] for i in range(3)] for a, b in ((0, 0), (1, 0), (1, 1), (0, 1))]
    path.write_text("".join(f"v {p[0]!r} {p[1]!r} {p[2]!r}\n" for p in pts) + "f 1 2 3\nf 1 3 4\n")


def mitsuba_scene(mi, path, out, emitter_samples, bsdf_samples):
    """The Mitsuba scene dict equivalent to dibench's scene file `path`."""
    sc = tomllib.loads(path.read_text())
    T = mi.ScalarTransform4f
    cam, img = sc["camera"], sc["image"]
    mats = {m["name"]: bsdf(m) for m in sc.get("material", [])}
    d = {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": emitter_samples, "bsdf_samples": bsdf_samples},
        "sensor": {
            "type": "perspective", "fov_axis": "y", "fov": float(cam["fov_y_deg"]),
            "to_world": T().look_at(origin=cam["eye"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])),
            "film": {"type": "hdrfilm", "width": img["width"], "height": img["height"],
                     "pixel_format": "rgb", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"},
        },
    }
    for i, q in enumerate(sc.get("quad", [])):
        obj = out / f"{path.stem}-quad{i}.obj"
        quad_obj(q, obj)
        d[f"quad{i}"] = area({"type": "obj", "filename": str(obj), "face_normals": True,
                              "bsdf": mats[q["material"]]}, q)
    for i, s in enumerate(sc.get("sphere", [])):
        d[f"sphere{i}"] = area({"type": "sphere", "center": s["center"], "radius": float(s["radius"]),
                                "bsdf": mats[s["material"]]}, s)
    for i, m in enumerate(sc.get("mesh", [])):
        t = m.get("transform", {})
        xf = (T().translate(t.get("translate", [0, 0, 0])) @ T().rotate([0, 1, 0], t.get("rotate_y_deg", 0.0))
              @ T().scale(t.get("scale", 1.0)))
        d[f"mesh{i}"] = area({"type": "obj", "filename": str(path.parent / m["file"]), "face_normals": True,
                              "to_world": xf, "bsdf": mats[m["material"]]}, m)
    for i, p in enumerate(sc.get("point_light", [])):
        inten = p.get("intensity") or [x / (4 * math.pi) for x in p["power"]]
        d[f"point{i}"] = {"type": "point", "position": p["position"], "intensity": rgb(inten)}
    for i, l in enumerate(sc.get("directional_light", [])):
        d[f"directional{i}"] = {"type": "directional", "direction": l["direction"],
                                "irradiance": rgb(l["irradiance"])}
    for i, l in enumerate(sc.get("linear_spot_light", [])):
        if "intensity" not in l:
            raise ValueError("linear_spot_light given by power: give `intensity` to compare with Mitsuba")
        pos, axis = l["position"], l["direction"]
        up = [1, 0, 0] if abs(axis[1]) > 0.99 * math.hypot(*axis) else [0, 1, 0]
        d[f"spot{i}"] = {"type": "spot", "intensity": rgb(l["intensity"]),
                         "cutoff_angle": float(l["cone_angle_deg"]),
                         "beam_width": float(l.get("falloff_start_deg", l["cone_angle_deg"])),
                         "to_world": T().look_at(origin=pos, target=[p + a for p, a in zip(pos, axis)], up=up)}
    if sc.get("spot_light"):
        raise ValueError("spot_light (smoothstep in cos θ) has no Mitsuba twin: use linear_spot_light")
    env = sc.get("environment")
    if env and "constant" in env:
        d["env"] = {"type": "constant", "radiance": rgb([x * env.get("scale", 1.0) for x in env["constant"]])}
    elif env:
        d["env"] = {"type": "envmap", "filename": str(path.parent / env["file"]),
                    "scale": float(env.get("scale", 1.0)),
                    "to_world": T().rotate([0, 1, 0], env.get("rotate_y_deg", 0.0) - 90.0)}
    return d, (img["width"], img["height"]), bool(env)


def time_mitsuba(mi, dr, scene, spp, seed):
    """(seconds, H×W×3 numpy image) of one render on one thread, evaluated and copied out.
    Loading (EXR and OBJ readers) deadlocks on a one-thread Dr.Jit pool in Mitsuba 3.9.1, so
    the pool has one thread only while rendering."""
    threads = dr.thread_count()
    dr.set_thread_count(1)
    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    arr = img.numpy()
    t = time.perf_counter() - t0
    dr.set_thread_count(threads)
    return t, arr


def run_dibench(exe, scene, strategies, seconds, out):
    """{strategy: (spp per second, its EXR)} from one `compare` run, at its last checkpoint, and
    the machine as the run's metadata names it (`cpu_model`: name, family, model, stepping, ISA)."""
    r = subprocess.run([exe, "compare", scene, "--strategies", ",".join(strategies), "--threads", "1",
                        "--time", str(seconds), "--reference-spp", "16", "--out", str(out)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"dibench compare {scene} failed:\n{r.stderr}")
    runs = [p for p in (out / scene).iterdir() if (p / "results.csv").is_file()]
    run = max(runs, key=lambda p: p.stat().st_mtime)
    last = {}
    with open(run / "results.csv") as f:
        for row in csv.DictReader(f):
            last[row["strategy"]] = row  # rows are in checkpoint order: the last one wins
    rates = {s: (int(last[s]["spp"]) / float(last[s]["time_s"]), run / f"{s}.exr") for s in strategies}
    with open(run / "run.json") as f:
        return rates, json.load(f)["cpu_model"]


def image_diffs(np, a, b, block=8):
    """Max per-channel relative difference of the image means, and the relative RMS difference of
    block×block block means as is and with `a` mirrored left-right (a mirroring shows up there)."""
    a, b = a[..., :3].astype(np.float64), b[..., :3].astype(np.float64)
    mean_rel = float(np.max(np.abs(a.mean((0, 1)) - b.mean((0, 1))) / b.mean((0, 1))))
    h, w = (b.shape[0] // block) * block, (b.shape[1] // block) * block

    def blocks(x):
        return x[:h, :w].reshape(h // block, block, w // block, block, 3).mean((1, 3))

    def rel(x):
        return float(np.sqrt(np.mean((blocks(x) - blocks(b)) ** 2)) / blocks(b).mean())
    return mean_rel, rel(a), rel(a[:, ::-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default="cornell,bunny,sphere_light,mesh_light,env_venice_bunny")
    ap.add_argument("--spp", type=int, default=256, help="Mitsuba samples per pixel per timed render")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--time", type=float, default=5.0, help="dibench seconds per strategy per round")
    ap.add_argument("--dibench", default="target/release/dibench")
    ap.add_argument("--baseline", help="a second dibench binary (say, the build before a change), run "
                    "in every round beside --dibench, the two in alternating order")
    ap.add_argument("--out", type=Path, help="output directory (default: a new temporary one)")
    args = ap.parse_args()
    out = (args.out or Path(tempfile.mkdtemp(prefix="bench-vs-mitsuba-"))).resolve()
    out.mkdir(parents=True, exist_ok=True)
    exe = str(Path(args.dibench).resolve())
    base_exe = str(Path(args.baseline).resolve()) if args.baseline else None
    mi, dr = import_mitsuba(out)
    import numpy as np

    scenes, mit_t, dib_t, base_t, diffs = {}, {}, {}, {}, {}
    for name in args.scenes.split(","):
        for est, (ne, nb) in ESTIMATORS.items():
            try:
                d, (w, h), env = mitsuba_scene(mi, Path("scenes") / f"{name}.toml", out, ne, nb)
            except (ValueError, KeyError, OSError) as e:
                sys.exit(f"{name}: cannot translate to Mitsuba: {e}")
            if env:
                strat = {"light": "env-latlong-hier", "mis-power": "mis-env-latlong-hier"}[est]
            elif est == "mis-power" and applies(exe, name, "mis-power-area"):
                strat = "mis-power-area"  # lights by area, as Mitsuba's `direct` samples them
            else:
                strat = est
            scene = mi.load_dict(d)
            time_mitsuba(mi, dr, scene, args.spp, 0)  # JIT compilation, untimed
            scenes[name, est] = (scene, w * h, strat)
    first_scene = args.scenes.split(",")[0]
    for r in range(1, args.rounds + 1):
        for name in args.scenes.split(","):
            for est in ESTIMATORS:
                scene, px, _ = scenes[name, est]
                time_mitsuba(mi, dr, scene, args.spp, 0)  # untimed: the first render after another
                t, diffs[name, est] = time_mitsuba(mi, dr, scene, args.spp, r)  # scene's runs slower
                mit_t.setdefault((name, est), []).append(px * args.spp / t)
            strats = [scenes[name, est][2] for est in ESTIMATORS]
            order = [(exe, dib_t, "dibench")] + ([(base_exe, base_t, "baseline")] if base_exe else [])
            for binary, times, tag in (order if r % 2 else order[::-1]):
                got, machine = run_dibench(binary, name, strats, args.time, out / f"{tag}-round{r}")
                if r == 1 and name == first_scene and tag == "dibench":
                    print(f"cpu: {machine}", flush=True)  # every figure names its machine
                for est in ESTIMATORS:
                    times.setdefault((name, est), []).append(scenes[name, est][1] * got[scenes[name, est][2]][0])
                if tag == "dibench":
                    res = got
            for est in ESTIMATORS:
                exr = res[scenes[name, est][2]][1]
                diffs[name, est] = image_diffs(np, diffs[name, est], np.array(mi.Bitmap(str(exr))))
            print(f"round {r} {name}: " + ", ".join(
                f"{e} mitsuba {mit_t[name, e][-1] / 1e6:.2f} M/s, dibench {dib_t[name, e][-1] / 1e6:.2f} M/s"
                + (f", baseline {base_t[name, e][-1] / 1e6:.2f} M/s" if base_exe else "")
                for e in ESTIMATORS), flush=True)

    rows = []
    print(f"\n{'scene':18} {'estimator':10} {'dibench strategy':22} {'mitsuba M/s min/med/max':>24} "
          f"{'dibench M/s min/med/max':>24} {'ratio':>6} {'mean Δ':>7} {'blocks':>6} {'mirr.':>6}"
          + (f" {'base ratio':>10} {'new/base':>8}" if base_exe else ""))
    for (name, est), (scene, px, strat) in scenes.items():
        m, b = sorted(mit_t[name, est]), sorted(dib_t[name, est])
        ratio = statistics.median(x / y for x, y in zip(dib_t[name, est], mit_t[name, est]))
        mean_rel, blk, mirr = diffs[name, est]
        fmt = lambda v: "/".join(f"{x / 1e6:.2f}" for x in (v[0], statistics.median(v), v[-1]))
        extra, cols = "", []
        if base_exe:
            bt = base_t[name, est]
            base_ratio = statistics.median(x / y for x, y in zip(bt, mit_t[name, est]))
            speedup = statistics.median(x / y for x, y in zip(dib_t[name, est], bt))
            extra = f" {base_ratio:10.2f} {speedup:8.3f}"
            cols = [f"{statistics.median(bt):.0f}", f"{base_ratio:.3f}", f"{speedup:.3f}"]
        print(f"{name:18} {est:10} {strat:22} {fmt(m):>24} {fmt(b):>24} {ratio:6.2f} {mean_rel:7.2%} "
              f"{blk:6.3f} {mirr:6.3f}" + extra)
        rows.append([name, est, f"{statistics.median(m):.0f}", f"{statistics.median(b):.0f}", f"{ratio:.3f}",
                     f"{mean_rel:.4f}", f"{blk:.4f}", f"{mirr:.4f}"] + cols)
    with open(out / "bench-vs-mitsuba.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["scene", "estimator", "mitsuba_samples_per_s", "dibench_samples_per_s", "ratio",
                     "image_mean_rel_diff", "block_rel_rms_diff", "block_rel_rms_diff_mirrored"]
                    + (["baseline_samples_per_s", "baseline_ratio", "speedup_over_baseline"] if base_exe else []))
        wr.writerows(rows)
    print(f"\nratio: median over rounds of dibench ÷ Mitsuba samples/s (interleaved); "
          f"mean Δ: max per-channel relative difference of the image means; blocks / mirr.: relative "
          f"RMS difference of 8×8-pixel block means, as is / one image mirrored"
          + ("; base ratio: the baseline's ratio; new/base: median of per-round dibench ÷ baseline" if base_exe else "")
          + ".\n"
          f"CSV: {out / 'bench-vs-mitsuba.csv'}")


if __name__ == "__main__":
    main()
