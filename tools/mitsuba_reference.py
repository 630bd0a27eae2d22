#!/usr/bin/env python3
"""Reference images of splitray's scenes from an independent renderer: Mitsuba 3.

    python3 -m venv tools/.venv-ref
    tools/.venv-ref/bin/pip install -r tools/requirements-reference.txt
    tools/.venv-ref/bin/python tools/mitsuba_reference.py            # the committed references

Renders scenes/cornell-box.{obj,mtl,toml} with Mitsuba's `path` integrator in the
`scalar_rgb` variant, set up to match `splitray render --integrator pt` exactly:

- geometry: the OBJ's triangles as they are (same vertices, same winding), one PLY per
  material with face normals (no smoothing: splitray shades with geometric normals when
  the OBJ has no `vn`);
- materials: Kd -> `diffuse` reflectance wrapped in `twosided` (splitray's Lambert is
  two-sided); Ke -> an `area` emitter of that radiance (one-sided, front = the winding's
  normal, as in splitray);
- camera: `perspective`, `fov` = the TOML's fov_y with `fov_axis="y"`, `to_world` =
  look_at(position, look_at, up) (Mitsuba's image x runs along forward x up, the same as
  splitray's `right`, so the red wall is on the left in both);
- film: `hdrfilm`, RGB, `box` reconstruction filter (a sample counts for the pixel it
  falls in, as splitray's jittered pixel sampling);
- integrator: `path` with the same max_depth (-1: unbounded) and rr_depth (5).

The per-pixel standard error comes from K independent renders (seeds 0..K-1): the
mean image is their average and stderr = std(images, ddof=1) / sqrt(K).
Writes <out>/<name>_{mean,stderr}.exr (float32 RGB).
"""

import argparse
import math
import os
import sys
import tempfile

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def parse_mtl(path):
    mats, cur = {}, None
    for line in open(path):
        t = line.split()
        if not t or t[0].startswith("#"):
            continue
        if t[0] == "newmtl":
            cur = mats.setdefault(t[1], {"Kd": [0.8] * 3, "Ke": [0.0] * 3})
        elif cur is not None and t[0] in ("Kd", "Ke"):
            cur[t[0]] = [float(x) for x in t[1:4]]
    return mats


def parse_obj(path):
    """Vertices and, per material, the triangles (fan-triangulated in file order)."""
    verts, groups, mat, mtllib = [], {}, "default", None
    for line in open(path):
        t = line.split()
        if not t or t[0].startswith("#"):
            continue
        if t[0] == "v":
            verts.append([float(x) for x in t[1:4]])
        elif t[0] == "mtllib":
            mtllib = t[1]
        elif t[0] == "usemtl":
            mat = t[1]
        elif t[0] == "f":
            idx = [int(x.split("/")[0]) for x in t[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            for k in range(1, len(idx) - 1):
                groups.setdefault(mat, []).append((idx[0], idx[k], idx[k + 1]))
    return np.array(verts, dtype=np.float64), groups, mtllib


def parse_camera(toml_path):
    import tomllib

    with open(toml_path, "rb") as f:
        doc = tomllib.load(f)
    cam = doc["camera"]
    return cam["position"], cam["look_at"], cam.get("up", [0.0, 1.0, 0.0]), cam["fov_y"]


def write_ply(path, verts, tris):
    """Binary PLY with unshared vertices (flat triangles, winding kept)."""
    pts = np.array([verts[i] for tri in tris for i in tri], dtype="<f4")
    with open(path, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"element vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\n"
                f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        f.write(pts.tobytes())
        for k in range(len(tris)):
            f.write(np.uint8(3).tobytes())
            f.write(np.array([3 * k, 3 * k + 1, 3 * k + 2], dtype="<i4").tobytes())


def scene_dict(obj, toml, width, height, spp, seed, max_depth, rr_depth, tmp):
    verts, groups, mtllib = parse_obj(obj)
    mats = parse_mtl(os.path.join(os.path.dirname(obj), mtllib)) if mtllib else {}
    position, look_at, up, fov_y = parse_camera(toml)
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth},
        "sensor": {
            "type": "perspective",
            "fov": fov_y,
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=position, target=look_at, up=up),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "pixel_format": "rgb",
                "component_format": "float32",
                "rfilter": {"type": "box"},
            },
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
    }
    for name, tris in groups.items():
        m = mats.get(name, {"Kd": [0.8] * 3, "Ke": [0.0] * 3})
        ply = os.path.join(tmp, f"{name}.ply")
        write_ply(ply, verts, tris)
        shape = {
            "type": "ply",
            "filename": ply,
            "face_normals": True,
            "bsdf": {
                "type": "twosided",
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["Kd"]}},
            },
        }
        if max(m["Ke"]) > 0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["Ke"]}}
        d[f"mesh_{name}"] = shape
    return d


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--obj", default=os.path.join(ROOT, "scenes/cornell-box.obj"))
    ap.add_argument("--toml", default=os.path.join(ROOT, "scenes/cornell-box.toml"))
    ap.add_argument("--name", default="cornell_pt_64")
    ap.add_argument("--out", default=os.path.join(ROOT, "tests/data/reference"))
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=512, help="samples per pixel of each of the K renders")
    ap.add_argument("--runs", type=int, default=16, help="K independent renders")
    ap.add_argument("--max-depth", type=int, default=-1)
    ap.add_argument("--rr-depth", type=int, default=5)
    args = ap.parse_args()

    images = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.runs):
            d = scene_dict(args.obj, args.toml, args.size, args.size, args.spp, k,
                           args.max_depth, args.rr_depth, tmp)
            scene = mi.load_dict(d)
            img = np.array(mi.render(scene, spp=args.spp, seed=k), dtype=np.float64)[:, :, :3]
            images.append(img)
            print(f"run {k + 1}/{args.runs}: mean {img.mean():.6f}", file=sys.stderr)
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    stderr = stack.std(axis=0, ddof=1) / math.sqrt(len(images))
    os.makedirs(args.out, exist_ok=True)
    for suffix, img in (("mean", mean), ("stderr", stderr)):
        path = os.path.join(args.out, f"{args.name}_{suffix}.exr")
        mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)
        print(f"wrote {path}", file=sys.stderr)
    print(
        f"{args.name}: {args.size}x{args.size}, {args.runs} x {args.spp} spp, image mean "
        f"{mean.mean():.6f} (rgb {mean.mean(axis=(0, 1))}), median relative stderr "
        f"{np.median(stderr / np.maximum(mean, 1e-9)):.4f}"
    )


if __name__ == "__main__":
    main()
