#!/usr/bin/env python3
"""Reference images of splitray's scenes from an independent renderer: Mitsuba 3.

    python3 -m venv tools/.venv-ref
    tools/.venv-ref/bin/pip install -r tools/requirements-reference.txt
    cargo build --release                                   # for `splitray export-scene`
    tools/.venv-ref/bin/python tools/mitsuba_reference.py   # every committed reference
    tools/.venv-ref/bin/python tools/mitsuba_reference.py glossy_path_64   # one of them

Writes, for each reference NAME of REFERENCES below, into tests/data/reference/:
NAME_mean.exr and NAME_stderr.exr (float32 RGB), NAME.scene.json (the scene it was
rendered from) and its entry in references.json (the manifest: scene, Mitsuba
integrator, max_depth, rr_depth, film, samples, variant, time taken, image mean). The
tests read the manifest (tests/suite/common/reference.rs), so a reference and the settings
splitray must match travel together.

The scene: `splitray export-scene SCENE --width W --height H -o NAME.scene.json`, not a
parse of the scene files here. splitray resolves a scene through its OBJ loader (fan
triangulation, winding), TOML transforms and [[material]] overrides, the MTL -> BSDF
mapping and its built-in generators (`fixture` exists only in code); a second parser
would drift from them silently. The export is what `pt` renders: triangles in order
with their winding, per-triangle materials, emission and BSDF layers as resolved, point
lights, camera, film. The tests compare the committed NAME.scene.json with the scene as
it exports today, so a reference goes stale loudly, never silently.

Mapping to Mitsuba 3, exact for every BSDF it accepts (anything else is refused):

- geometry: one PLY per material, the triangles' own vertices and winding, face
  normals (splitray shades with geometric normals where a mesh has no `vn`; a scene
  with shading normals is refused);
- Lambert (albedo) -> `twosided` `diffuse` (splitray's reflection-only BSDFs are
  two-sided);
- mirror (tint) -> `twosided` `conductor`, no material preset (eta = 0, k = 1: the
  complex index i, whose Fresnel reflectance is exactly 1), specular_reflectance = tint;
- microfacet reflection (GGX, Schlick F0 = 1, alpha) -> `twosided` `roughconductor`
  with no material preset (Fresnel exactly 1, as Schlick's with F0 = 1) and the same
  alpha. Mitsuba's GGX D and its Smith G1 are splitray's, but Mitsuba combines them as
  the separable G1(wi) G1(wo) while splitray uses the height-correlated
  1 / (1 + L(wi) + L(wo)) (L = 1/G1 - 1). With --shadowing height-correlated (the
  default) the conductor is `splitray_roughconductor`, registered below: Mitsuba's own
  MicrofacetDistribution (D, G1, visible-normal sampling) with G1s combined the
  height-correlated way, everything else as `roughconductor`: the reference is exact.
  --shadowing separable uses stock `roughconductor`, to measure the difference;
  any other F0 or distribution is refused (no exact counterpart);
- emission Le -> an `area` emitter of radiance Le (one-sided, front = the winding's
  normal, as in splitray); point lights -> `point` of that intensity;
- camera: `perspective`, fov = fov_y with fov_axis "y", to_world = look_at(position,
  look_at, up) (Mitsuba's image x runs along forward x up, splitray's `right`);
- film: `hdrfilm`, RGB, `box` reconstruction filter (a sample counts for the pixel it
  falls in, as splitray's jittered pixel sampling and light-tracing splats).

Integrators, depth counted as in splitray (src/integrator/pt/mod.rs): max_depth 1 shows
only emitters seen directly, 2 adds direct light, -1 is unbounded; rr_depth 5.
- `path`: Mitsuba's unidirectional path tracer (the reference of `pt`).
- `ptracer`: Mitsuba's particle (light) tracer, for `fixture`, whose light hides in a
  box so that nearly all light reaches the camera indirectly. It counts depth the same
  way: directly visible emitters are connected to the sensor as depth 1
  (sample_visible_emitters; not hidden, as hide_emitters is false), the light path's
  first hit connected to the camera is depth 2, and a light path continues while
  depth < max_depth; Russian roulette from depth > rr_depth (a different start than
  `path`'s depth >= rr_depth, which changes noise, not the expectation).

Statistics: a reference is K independent runs (every pass its own seed); each run is
P passes of S spp. mean = the average of the K run images, stderr = std(runs, ddof=1)
/ sqrt(K), per pixel and channel.

Variants: `scalar_rgb` needs nothing but the wheel. `llvm_ad_rgb` compiles the whole
renderer, the Python BSDF above included, with LLVM (about 2x faster for `path` here,
and 8x with `splitray_roughconductor`, which `scalar_rgb` calls through Python per
sample); drjit needs libLLVM >= 16 for it (Debian 12: `apt-get install libllvm19`; the
script finds it, or set DRJIT_LIBLLVM_PATH). The two agree (see below).

The committed references, all 64x64, max_depth -1, rr_depth 5, Mitsuba 3.9.1 on 2
cores shared with other builds (load average 7-12 while they ran):

  NAME                SCENE               INTEGRATOR  K x P x S      VARIANT      TIME
  cornell_path_64     cornell-box         path        16 x  8 x 128  scalar_rgb    288 s
  glossy_path_64      scenes/glossy.toml  path        16 x  8 x 512  llvm_ad_rgb   676 s
  mirror_path_64      scenes/mirror.toml  path        16 x  8 x 512  llvm_ad_rgb   700 s
  fixture_ptracer_64  fixture             ptracer     16 x 16 x 128  scalar_rgb   1777 s

The caustic scenes have 4x the samples of the Cornell box so that the reference stays
far more precise than a test's render where a path tracer's pixels are skewed.
references.json records each one's seconds, image mean and the mean's standard error
(0.015-0.031%).

Cross-checks, with the statistics of the tests (image mean, pixel channels beyond
3 sigma, largest 8x8-block |z|):
- `path` in llvm_ad_rgb vs the scalar_rgb Cornell box reference (16 x 1024 spp each):
  -0.03%, 0.52%, 2.9;
- `ptracer` vs `path` on the Cornell box (16 x 1024 spp each): -0.03%, 0.63%, 2.4;
- `path` (16 x 4096 spp) vs the `ptracer` reference of `fixture`: -0.04%, 0.73%, 2.7;
- `ptracer` vs `path` on the Cornell box at max_depth 2 and 3 (depth conventions):
  -0.03% and -0.02%, 0.62% and 0.83%, 2.3 and 2.9;
- stock `roughconductor` (separable G) vs the exact glossy reference: -0.13% on the
  image mean, down to -4% on pixels of the metal (1st percentile); splitray's `pt` at
  4096 spp tells them apart (8x8 blocks at 6.7 sigma from the stock one, 2.3 from the
  exact one; image mean +0.15% vs +0.02%).
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import mitsuba as mi

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# name -> scene (a built-in name or a path relative to the repository root), Mitsuba
# integrator, max_depth, rr_depth, film size, runs K, passes P per run, spp S per pass,
# Mitsuba variant.
REFERENCES = {
    "cornell_path_64": dict(scene="cornell-box", integrator="path", max_depth=-1,
                            rr_depth=5, size=64, runs=16, passes=8, spp=128,
                            variant="scalar_rgb"),
    "glossy_path_64": dict(scene="scenes/glossy.toml", integrator="path", max_depth=-1,
                           rr_depth=5, size=64, runs=16, passes=8, spp=512,
                           variant="llvm_ad_rgb"),
    "mirror_path_64": dict(scene="scenes/mirror.toml", integrator="path", max_depth=-1,
                           rr_depth=5, size=64, runs=16, passes=8, spp=512,
                           variant="llvm_ad_rgb"),
    "fixture_ptracer_64": dict(scene="fixture", integrator="ptracer", max_depth=-1,
                               rr_depth=5, size=64, runs=16, passes=16, spp=128,
                               variant="scalar_rgb"),
}

# drjit's LLVM backend (the llvm_ad_rgb variant) needs libLLVM >= 16; Debian 12 has
# LLVM 19 in `libllvm19`. DRJIT_LIBLLVM_PATH, when set, wins.
LIBLLVM_CANDIDATES = ["/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
                      "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"]
for candidate in LIBLLVM_CANDIDATES:
    if os.path.exists(candidate):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", candidate)
        break

EXPORT_FORMAT, EXPORT_VERSION = "splitray-scene", 1
MANIFEST = "references.json"


def export_scene(splitray, spec, width, height, path):
    """The scene as splitray resolves it (`splitray export-scene`)."""
    cmd = [splitray, "export-scene", spec, "-o", path, "--width", str(width),
           "--height", str(height)]
    subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    with open(path) as f:
        scene = json.load(f)
    if (scene.get("format"), scene.get("version")) != (EXPORT_FORMAT, EXPORT_VERSION):
        sys.exit(f"{path}: not a {EXPORT_FORMAT} v{EXPORT_VERSION} export")
    return scene


def register_height_correlated_conductor():
    """`splitray_roughconductor`: Mitsuba's `roughconductor` (GGX, visible-normal
    sampling, Fresnel 1) with Smith's height-correlated masking-shadowing
    G = 1 / (1 + L(wi) + L(wo)) = 1 / (1/G1(wi) + 1/G1(wo) - 1), as splitray evaluates
    it (src/bsdf/microfacet.rs), instead of the separable G1(wi) G1(wo). D, G1 and the
    sampling are Mitsuba's MicrofacetDistribution; only the combination differs."""
    import drjit as dr

    class HeightCorrelatedConductor(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.alpha = props.get("alpha")
            self.m_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def distribution(self):
            return mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)

        @staticmethod
        def g(distr, wi, wo, m):
            g1i, g1o = distr.smith_g1(wi, m), distr.smith_g1(wo, m)
            ok = (g1i > 0) & (g1o > 0)
            return dr.select(ok, dr.rcp(dr.rcp(g1i) + dr.rcp(g1o) - 1.0), 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            active = active & (cos_i > 0)
            distr = self.distribution()
            m, pdf_m = distr.sample(si.wi, sample2)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.reflect(si.wi, m)
            bs.eta = 1.0
            bs.sampled_component = 0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            active &= (pdf_m != 0) & (mi.Frame3f.cos_theta(bs.wo) > 0)
            bs.pdf = pdf_m / (4.0 * dr.dot(bs.wo, m))
            # f cos / pdf with pdf_m = D G1(wi) (wi.m) / cos_i and wo.m = wi.m: G / G1(wi).
            g1i = distr.smith_g1(si.wi, m)
            weight = dr.select(g1i > 0, self.g(distr, si.wi, bs.wo, m) / g1i, 0.0)
            return bs, mi.Color3f(dr.select(active, weight, 0.0))

        def eval(self, ctx, si, wo, active=True):
            cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
            active = active & (cos_i > 0) & (cos_o > 0)
            h = dr.normalize(wo + si.wi)
            distr = self.distribution()
            value = distr.eval(h) * self.g(distr, si.wi, wo, h) / (4.0 * cos_i)
            return mi.Color3f(dr.select(active, value, 0.0))

        def pdf(self, ctx, si, wo, active=True):
            cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
            h = dr.normalize(wo + si.wi)
            active = (active & (cos_i > 0) & (cos_o > 0) & (dr.dot(si.wi, h) > 0)
                      & (dr.dot(wo, h) > 0))
            distr = self.distribution()
            value = distr.eval(h) * distr.smith_g1(si.wi, h) / (4.0 * cos_i)
            return dr.select(active, value, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def to_string(self):
            return f"HeightCorrelatedConductor[alpha={self.alpha}]"

    mi.register_bsdf("splitray_roughconductor", lambda props: HeightCorrelatedConductor(props))


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def bsdf_dict(material, shadowing):
    """The Mitsuba BSDF of one exported material, or an error naming what has no exact
    counterpart."""
    name, layers = material["name"], material["layers"]
    if len(layers) != 1 or layers[0]["weight"] != 1.0:
        sys.exit(f"material '{name}': a mixture of {len(layers)} layers has no exact Mitsuba counterpart here")
    layer = layers[0]
    kind = layer["kind"]
    if kind == "lambert":
        inner = {"type": "diffuse", "reflectance": rgb(layer["albedo"])}
    elif kind == "mirror":
        inner = {"type": "conductor", "material": "none", "specular_reflectance": rgb(layer["tint"])}
    elif kind == "microfacet-reflection":
        if layer["f0"] != [1.0, 1.0, 1.0] or layer["distribution"] != "ggx":
            sys.exit(f"material '{name}': only GGX with F0 = 1 maps exactly (Schlick = 1 = "
                     f"Mitsuba's Fresnel with eta = i); got F0 {layer['f0']}, {layer['distribution']}")
        if layer["shadowing"] != "smith-height-correlated":
            sys.exit(f"material '{name}': unknown shadowing '{layer['shadowing']}'")
        alpha = float(layer["roughness"])
        if shadowing == "height-correlated":
            inner = {"type": "splitray_roughconductor", "alpha": alpha}
        else:
            inner = {"type": "roughconductor", "material": "none", "distribution": "ggx",
                     "alpha": alpha}
    else:
        sys.exit(f"material '{name}': BSDF kind '{kind}' has no exact Mitsuba mapping here")
    return {"type": "twosided", "bsdf": inner}


def write_ply(path, triangles):
    """Binary PLY with unshared vertices (flat triangles, winding kept)."""
    pts = np.array([t["p"] for t in triangles], dtype="<f4").reshape(-1, 3)
    faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"] = 3
    faces["i"] = np.arange(3 * len(triangles), dtype="<i4").reshape(-1, 3)
    with open(path, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"element vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\n"
                f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        f.write(pts.tobytes())
        f.write(faces.tobytes())


def scene_dict(scene, ref, shadowing, tmp):
    cam, film = scene["camera"], scene["film"]
    integrator = {"type": ref["integrator"], "max_depth": ref["max_depth"],
                  "rr_depth": ref["rr_depth"]}
    d = {
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective",
            "fov": cam["fov_y"],
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam["position"], target=cam["look_at"], up=cam["up"]),
            "film": {
                "type": "hdrfilm",
                "width": film["width"],
                "height": film["height"],
                "pixel_format": "rgb",
                "component_format": "float32",
                "rfilter": {"type": "box"},
            },
            "sampler": {"type": "independent", "sample_count": ref["spp"]},
        },
    }
    by_material = {}
    for t in scene["triangles"]:
        if t["normals"] is not None:
            sys.exit("the scene has shading normals: not mapped to Mitsuba here")
        by_material.setdefault(t["material"], []).append(t)
    for index, tris in sorted(by_material.items()):
        m = scene["materials"][index]
        ply = os.path.join(tmp, f"material{index}.ply")
        write_ply(ply, tris)
        shape = {"type": "ply", "filename": ply, "face_normals": True,
                 "bsdf": bsdf_dict(m, shadowing)}
        if max(m["emission"]) > 0:
            shape["emitter"] = {"type": "area", "radiance": rgb(m["emission"])}
        d[f"material{index}"] = shape
    for k, light in enumerate(scene["point_lights"]):
        d[f"point{k}"] = {"type": "point", "position": light["position"],
                          "intensity": rgb(light["intensity"])}
    return d


def render(name, ref, scene, args, tmp):
    """K run images (each the mean of P passes) of one reference."""
    mi_scene = mi.load_dict(scene_dict(scene, ref, args.shadowing, tmp))
    runs = []
    for k in range(ref["runs"]):
        acc = None
        for p in range(ref["passes"]):
            seed = k * ref["passes"] + p
            img = np.array(mi.render(mi_scene, spp=ref["spp"], seed=seed), dtype=np.float64)
            acc = img[:, :, :3] if acc is None else acc + img[:, :, :3]
        runs.append(acc / ref["passes"])
        print(f"{name}: run {k + 1}/{ref['runs']}: mean {runs[-1].mean():.6f}", file=sys.stderr)
    return np.stack(runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help="references to render (default: all of REFERENCES)")
    ap.add_argument("--out", default=os.path.join(ROOT, "tests/data/reference"))
    ap.add_argument("--splitray", default=os.path.join(ROOT, "target/release/splitray"))
    ap.add_argument("--runs", type=int, help="override K (quick looks; the manifest records what ran)")
    ap.add_argument("--passes", type=int, help="override P")
    ap.add_argument("--spp", type=int, help="override S")
    ap.add_argument("--integrator", choices=["path", "ptracer"], help="override the integrator")
    ap.add_argument("--scene", help="override the scene (a built-in name or a scene file)")
    ap.add_argument("--max-depth", type=int, help="override max_depth")
    ap.add_argument("--suffix", default="", help="appended to each output name")
    ap.add_argument("--shadowing", choices=["height-correlated", "separable"],
                    default="height-correlated",
                    help="GGX masking-shadowing: splitray's (exact) or stock roughconductor's")
    ap.add_argument("--variant", help="override the Mitsuba variant (scalar_rgb, llvm_ad_rgb)")
    args = ap.parse_args()

    names = args.names or list(REFERENCES)
    unknown = [n for n in names if n not in REFERENCES]
    if unknown:
        sys.exit(f"unknown reference(s) {unknown}; known: {list(REFERENCES)}")
    os.makedirs(args.out, exist_ok=True)
    manifest_path = os.path.join(args.out, MANIFEST)
    manifest = {}
    if os.path.exists(manifest_path):
        with open(manifest_path) as f:
            manifest = json.load(f)

    for name in names:
        ref = dict(REFERENCES[name])
        for key in ("runs", "passes", "spp", "integrator", "scene", "variant", "max_depth"):
            if getattr(args, key) is not None:
                ref[key] = getattr(args, key)
        out_name = name + args.suffix
        mi.set_variant(ref["variant"])
        register_height_correlated_conductor()
        with tempfile.TemporaryDirectory() as tmp:
            scene_path = os.path.join(tmp, "scene.json")
            scene = export_scene(args.splitray, ref["scene"], ref["size"], ref["size"], scene_path)
            start = time.time()
            runs = render(out_name, ref, scene, args, tmp)
            seconds = time.time() - start
            shutil.copyfile(scene_path, os.path.join(args.out, f"{out_name}.scene.json"))
        k = len(runs)
        mean = runs.mean(axis=0)
        stderr = runs.std(axis=0, ddof=1) / math.sqrt(k)
        run_means = runs.mean(axis=(1, 2, 3))
        image_mean = float(mean.mean())
        image_mean_se = float(run_means.std(ddof=1) / math.sqrt(k))
        for suffix, img in (("mean", mean), ("stderr", stderr)):
            path = os.path.join(args.out, f"{out_name}_{suffix}.exr")
            mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)
        manifest[out_name] = {
            "scene": ref["scene"],
            "integrator": ref["integrator"],
            "max_depth": ref["max_depth"],
            "rr_depth": ref["rr_depth"],
            "width": ref["size"],
            "height": ref["size"],
            "runs": k,
            "spp_per_run": ref["passes"] * ref["spp"],
            "mitsuba": mi.__version__,
            "variant": ref["variant"],
            "conductor_shadowing": args.shadowing,
            "seconds": round(seconds, 1),
            "image_mean": image_mean,
            "image_mean_stderr": image_mean_se,
            "median_relative_stderr": float(np.median(stderr / np.maximum(mean, 1e-9))),
        }
        with open(manifest_path + ".tmp", "w") as f:
            json.dump(manifest, f, indent=2, sort_keys=True)
            f.write("\n")
        os.replace(manifest_path + ".tmp", manifest_path)
        print(
            f"{out_name}: {ref['integrator']} max_depth {ref['max_depth']}, "
            f"{ref['size']}x{ref['size']}, {k} x {ref['passes']} x {ref['spp']} spp in "
            f"{seconds:.0f} s; image mean {image_mean:.6f} +- {image_mean_se / image_mean * 100:.3f}% "
            f"(rgb {mean.mean(axis=(0, 1))}), median relative stderr "
            f"{manifest[out_name]['median_relative_stderr']:.4f}"
        )


if __name__ == "__main__":
    main()
