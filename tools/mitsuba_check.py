#!/usr/bin/env python3
"""Cross-check of `parallax path` against Mitsuba 3's `path` integrator (not run by CI).

Renders one scene, camera, light rig and the diffuse material model (`--materials diffuse`:
every opaque surface a two-sided Lambertian of its base colour or texture, glass a thin
dielectric of index 1.5) with both renderers at equal spp, and compares:

* agreement: the mean over pixels of (ours - Mitsuba) against its standard error (from both
  renderers' per-pixel variances of the mean), the per-pixel z-scores
  (ours - Mitsuba) / sqrt(var_ours + var_mitsuba), and the mean luminance (within 1%);
* speed: paths/s of each at the same spp and thread count, best of --rounds interleaved
  rounds (Mitsuba after a warm-up run that compiles its kernel; both times exclude loading
  and the acceleration structure build);
* equal-time error: RMSE of each against a high-spp reference (the mean of both renderers'
  reference renders), ours re-rendered with `--time-budget` = Mitsuba's time.

The scene reaches Mitsuba through `parallax path --export-mitsuba DIR` (PLY meshes, EXR
textures, scene.json), so both renderers read the same resolved geometry, camera and lights.

Usage (from the repository root; extra arguments after `--` go to `parallax path`):

    python3 tools/mitsuba_check.py --out out/mitsuba/cornell --width 320 --height 320 \\
        --spp 256 --threads 2 -- --scene cornell --camera front

    python3 tools/mitsuba_check.py --out out/mitsuba/sponza --width 320 --height 180 \\
        --spp 256 -- --scene ../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb \\
        --eye=-9,3.5,0 --target=8,5,0 --fov-y 60

Needs `pip install mitsuba numpy`. The llvm variant needs a libLLVM that Dr.Jit accepts
(LLVM 19 from Debian's libllvm19 works; 14 and 15 fail to compile its kernels): the script
points DRJIT_LIBLLVM_PATH at the newest /usr/lib/x86_64-linux-gnu/libLLVM*.so it finds unless
it is set. Pass --variant scalar_rgb to run without LLVM (much slower).
"""

import argparse
import glob
import json
import os
import re
import subprocess
import sys
import time


def newest_llvm():
    libs = glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM*.so*") + glob.glob(
        "/usr/lib/llvm-*/lib/libLLVM*.so*"
    )

    def version(p):
        m = re.search(r"LLVM[-.]?(\d+)", os.path.basename(p))
        return int(m.group(1)) if m else 0

    libs.sort(key=version)
    return libs[-1] if libs else None


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--reference-spp", type=int, default=0, help="spp of the reference renders (default 16x --spp)")
    ap.add_argument("--max-depth", type=int, default=16)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--parallax", default="target/release/parallax", help="the parallax binary")
    ap.add_argument("--skip-reference", action="store_true", help="only the equal-spp check and speed")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved timing rounds (best kept)")
    ap.add_argument("rest", nargs=argparse.REMAINDER, help="-- then scene, camera and light flags of parallax path")
    a = ap.parse_args()
    if a.rest and a.rest[0] == "--":
        a.rest = a.rest[1:]
    return a


def run_parallax(a, out_exr, spp, seed, extra=(), export=None, time_budget=None):
    cmd = [
        a.parallax, "--quiet", "--threads", str(a.threads), "path",
        "--materials", "diffuse", "--width", str(a.width), "--height", str(a.height),
        "--max-depth", str(a.max_depth), "--seed", str(seed), "--out", out_exr,
        "--stats", out_exr + ".json",
    ]
    if time_budget is not None:
        cmd += ["--time-budget", f"{time_budget:.3f}"]
    else:
        cmd += ["--spp", str(spp)]
    if export:
        cmd += ["--export-mitsuba", export]
    cmd += list(a.rest) + list(extra)
    subprocess.run(cmd, check=True)
    with open(out_exr + ".json") as f:
        return json.load(f)


def read_ours(path):
    import mitsuba as mi
    import numpy as np

    bmp = mi.Bitmap(path)
    arr = np.array(bmp, dtype=np.float64)
    names = [f.name for f in bmp.struct_()]
    get = lambda n: arr[..., names.index(n)]
    rgb = np.stack([get("R"), get("G"), get("B")], -1)
    var = np.stack([get("variance.R"), get("variance.G"), get("variance.B")], -1)
    return rgb, var


def mitsuba_scene(mi, export_dir, spp, seed, moment):
    with open(os.path.join(export_dir, "scene.json")) as f:
        doc = json.load(f)
    cam, film, integ = doc["camera"], doc["film"], doc["integrator"]
    path = {"type": "path", "max_depth": integ["max_depth"], "rr_depth": integ["rr_depth"]}
    scene = {
        "type": "scene",
        "integrator": {"type": "moment", "nested": path} if moment else path,
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": cam["fov_y_deg"],
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["eye"], target=cam["target"], up=cam["up"]),
            "film": {
                "type": "hdrfilm", "width": film["width"], "height": film["height"],
                "rfilter": {"type": "box"}, "pixel_format": "rgb", "component_format": "float32",
            },
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
    }
    rgb = lambda v: {"type": "rgb", "value": v}
    env = doc["environment"]
    if max(env) > 0:
        scene["environment"] = {"type": "constant", "radiance": rgb(env)}
    for i, l in enumerate(doc["lights"]):
        if l["type"] == "point":
            scene[f"light{i}"] = {"type": "point", "position": l["position"], "intensity": rgb(l["intensity"])}
        elif l["type"] == "directional":
            scene[f"light{i}"] = {"type": "directional", "direction": l["direction"], "irradiance": rgb(l["irradiance"])}
        else:
            raise SystemExit(f"unsupported light {l['type']}")
    for i, s in enumerate(doc["shapes"]):
        b = s["bsdf"]
        if b["type"] == "thindielectric":
            bsdf = {"type": "thindielectric", "int_ior": b["int_ior"], "ext_ior": b["ext_ior"]}
        else:
            if "texture" in b:
                refl = {
                    "type": "bitmap", "filename": os.path.join(export_dir, b["texture"]),
                    "filter_type": "bilinear", "wrap_mode": b["wrap_mode"], "raw": True,
                }
            else:
                refl = rgb(b["reflectance"])
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}
        shape = {
            "type": "ply", "filename": os.path.join(export_dir, s["file"]),
            "face_normals": s["face_normals"], "bsdf": bsdf,
        }
        if s["emission"] is not None:
            shape["emitter"] = {"type": "area", "radiance": rgb(s["emission"])}
        scene[f"shape{i:04}"] = shape
    return mi.load_dict(scene), doc


def render_mitsuba(mi, dr, export_dir, spp, seed, moment):
    import numpy as np

    scene, _ = mitsuba_scene(mi, export_dir, spp, seed, moment)
    t = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    arr = np.array(img, dtype=np.float64)
    return arr, time.perf_counter() - t


def luminance(img):
    return 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]


def main():
    a = parse_args()
    if a.variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = newest_llvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    mi.set_variant(a.variant)
    if hasattr(dr, "set_thread_count"):
        dr.set_thread_count(a.threads)
    os.makedirs(a.out, exist_ok=True)
    export = os.path.join(a.out, "export")
    seed = 1

    # 1. Ours at --spp (and the export).
    ours_exr = os.path.join(a.out, "ours.exr")
    ours_stats = run_parallax(a, ours_exr, a.spp, seed, export=export)
    ours, ours_var = read_ours(ours_exr)

    # 2. Mitsuba at --spp: the moment integrator gives each pixel's first and second moment.
    mom, _ = render_mitsuba(mi, dr, export, a.spp, seed, moment=True)
    m1, m2 = mom[..., 0:3], mom[..., 3:6]
    n = a.spp
    mit = m1
    mit_var = np.maximum(m2 - m1 * m1, 0.0) * n / max(n - 1, 1) / n
    mi.Bitmap(mit.astype(np.float32)).write(os.path.join(a.out, "mitsuba.exr"))

    # Agreement.
    diff = ours - mit
    comb = ours_var + mit_var
    d_mean = diff.mean()
    d_se = np.sqrt(comb.sum()) / diff.size
    # Pixels where both variances vanish (e.g. plain sky seen directly) carry no z-score.
    valid = comb > 1e-10
    z = diff[valid] / np.sqrt(comb[valid])
    lum_o, lum_m = luminance(ours).mean(), luminance(mit).mean()
    lum_rel = (lum_o - lum_m) / lum_m if lum_m > 0 else float("nan")

    # 3. Speed: interleaved rounds, ours then Mitsuba's plain path integrator (its kernel
    # compiled by a warm-up run), best round of each. Both times exclude loading and the
    # acceleration structure build.
    render_mitsuba(mi, dr, export, a.spp, seed + 1, moment=False)
    t_ours, t_mit = ours_stats["seconds"], float("inf")
    round_pairs = []
    for r in range(a.rounds):
        st = run_parallax(a, os.path.join(a.out, "timing.exr"), a.spp, seed + 10 + r)
        t_ours = min(t_ours, st["seconds"])
        _, t = render_mitsuba(mi, dr, export, a.spp, seed + 2, moment=False)
        t_mit = min(t_mit, t)
        round_pairs.append({"seconds_ours": st["seconds"], "seconds_mitsuba": t})
    paths = a.width * a.height * a.spp

    result = {
        "scene": ours_stats["scene"],
        "width": a.width, "height": a.height, "spp": a.spp, "max_depth": a.max_depth,
        "threads": a.threads, "variant": a.variant, "rounds": a.rounds, "parallax_args": a.rest,
        "mean_diff": d_mean, "mean_diff_se": d_se, "mean_diff_in_se": d_mean / d_se,
        "z_abs_gt3_fraction": float((np.abs(z) > 3).mean()),
        "z_mean": float(z.mean()), "z_median": float(np.median(z)),
        "lum_ours": lum_o, "lum_mitsuba": lum_m, "lum_rel_diff": lum_rel,
        "seconds_ours": t_ours, "seconds_mitsuba": t_mit,
        "paths_per_s_ours": paths / t_ours, "paths_per_s_mitsuba": paths / t_mit,
    }
    result["agree"] = bool(abs(d_mean) <= 3 * d_se and abs(lum_rel) <= 0.01)
    # Every interleaved round, ours then Mitsuba's (on a loaded host the pairs, not the best of
    # each, say whether a difference holds).
    for p in round_pairs:
        p["paths_per_s_ratio"] = p["seconds_mitsuba"] / p["seconds_ours"]
    result["rounds_timed"] = round_pairs

    if not a.skip_reference:
        ref_spp = a.reference_spp or 16 * a.spp
        ref_o_exr = os.path.join(a.out, "reference_ours.exr")
        run_parallax(a, ref_o_exr, ref_spp, seed + 100)
        ref_o, _ = read_ours(ref_o_exr)
        ref_m, _ = render_mitsuba(mi, dr, export, ref_spp, seed + 200, moment=False)
        mi.Bitmap(ref_m.astype(np.float32)).write(os.path.join(a.out, "reference_mitsuba.exr"))
        ref = 0.5 * (ref_o + ref_m)
        # Agreement again at the reference's spp (a tighter luminance comparison).
        lr_o, lr_m = luminance(ref_o).mean(), luminance(ref_m).mean()
        result["lum_rel_diff_reference"] = (lr_o - lr_m) / lr_m if lr_m > 0 else float("nan")
        rmse = lambda img: float(np.sqrt(((img - ref) ** 2).mean()))
        # Ours at Mitsuba's time.
        eq_exr = os.path.join(a.out, "ours_equal_time.exr")
        eq_stats = run_parallax(a, eq_exr, 0, seed + 3, time_budget=t_mit)
        eq, _ = read_ours(eq_exr)
        result.update({
            "reference_spp": ref_spp,
            "rmse_ours_equal_spp": rmse(ours), "rmse_mitsuba_equal_spp": rmse(mit),
            "rmse_ours_equal_time": rmse(eq), "spp_ours_equal_time": eq_stats["spp"],
            "seconds_ours_equal_time": eq_stats["seconds"],
            "efficiency_ratio": (rmse(mit) ** 2 * t_mit) / (rmse(ours) ** 2 * t_ours),
        })
        # The equal-time RMSE ratio each timed round predicts (error ~ 1/sqrt(paths): the
        # equal-spp ratio times sqrt(paths/s Mitsuba / ours)); less noisy on a loaded host than
        # the one budget run above.
        spp_ratio = rmse(ours) / rmse(mit)
        for p in round_pairs:
            p["rmse_equal_time_ratio_predicted"] = spp_ratio * (p["paths_per_s_ratio"] ** -0.5)

    with open(os.path.join(a.out, "result.json"), "w") as f:
        json.dump(result, f, indent=2)
    print(json.dumps(result, indent=2))
    return 0 if result["agree"] else 1


if __name__ == "__main__":
    sys.exit(main())
