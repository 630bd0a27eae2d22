//! The GLSL BSDFs (`glsl/common/bsdf.glsl`, through the test kernels in `glsl/bsdf/`)
//! against their Rust twins: struct layout, eval/pdf and sample on thousands of random
//! configurations per BSDF type, and χ² tests of samples drawn on the GPU.

use crate::common;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use splitray::bsdf::chi2::{self, Chi2Settings};
use splitray::bsdf::key::{key_id, key_type};
use splitray::bsdf::sampling::uniform_sphere;
use splitray::bsdf::{
    kernel_constants, kind, layer_kinds, material_key, Bsdf, BsdfFlags, BsdfLayer, BsdfParams,
    BsdfSample, Distribution, MaterialType, TransportMode,
};
use splitray::shaders;
use splitray::vk::{Buffer, ComputePipeline, Gpu, PipelineDesc, StreamKind};

/// `EvalQuery` in glsl/bsdf/eval_test.comp (32 bytes).
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
#[repr(C)]
struct EvalQuery {
    wo: [f32; 3],
    params: u32,
    wi: [f32; 3],
    mode: u32,
}

/// `SampleQuery` in glsl/bsdf/sample_test.comp (32 bytes).
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
#[repr(C)]
struct SampleQuery {
    wo: [f32; 3],
    params: u32,
    u: [f32; 3],
    mode: u32,
}

/// `SampleResult` in glsl/bsdf/sample_test.comp (48 bytes).
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
#[repr(C)]
struct SampleResult {
    f: [f32; 3],
    pdf: f32,
    wi: [f32; 3],
    flags: u32,
    eta: f32,
    layer: u32,
    valid: u32,
    pad: u32,
}

fn uniforms(n: usize, seed: u64) -> Vec<f32> {
    common::random_u32s(n, seed)
        .into_iter()
        .map(|x| (x >> 8) as f32 / (1u32 << 24) as f32)
        .collect()
}

fn mode_of(m: u32) -> TransportMode {
    if m == 0 {
        TransportMode::Radiance
    } else {
        TransportMode::Importance
    }
}

fn run_kernel<Q: Pod, R: Pod>(
    gpu: &Gpu,
    kernel: splitray::shaders::Kernel,
    params: &[BsdfParams],
    queries: &[Q],
) -> Vec<R> {
    run_specialized(gpu, kernel, params, queries, &[64])
}

/// [`run_kernel`] with the specialization constants `spec` (0: the workgroup size; 2:
/// `BSDF_KINDS`; as `kernel_constants` makes them).
fn run_specialized<Q: Pod, R: Pod>(
    gpu: &Gpu,
    kernel: splitray::shaders::Kernel,
    params: &[BsdfParams],
    queries: &[Q],
    spec: &[u32],
) -> Vec<R> {
    let pipeline = ComputePipeline::new(
        gpu,
        &PipelineDesc {
            kernel,
            bindings: 3,
            push_constant_bytes: 4,
            spec,
        },
    )
    .unwrap();
    let pb: Buffer = gpu.upload("bsdf params", params).unwrap();
    let qb = gpu.upload("queries", queries).unwrap();
    let rb = gpu.zeroed::<R>("results", queries.len()).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    let n = queries.len() as u32;
    rec.dispatch_items(
        &pipeline,
        &[(&pb).into(), (&qb).into(), (&rb).into()],
        &n,
        n as u64,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    rb.read::<R>().unwrap()
}

/// Random parameter records of one BSDF kind (`kind::COUNT` for random layered stacks).
fn random_params(which: u32, count: usize, seed: u64) -> Vec<BsdfParams> {
    let r = uniforms(count * 40, seed);
    let mut at = 0;
    let mut next = || {
        at += 1;
        r[at - 1]
    };
    let layer = |k: u32, next: &mut dyn FnMut() -> f32| -> BsdfLayer {
        let rgb = Vec3::new(next(), next(), next());
        let dist = Distribution::from_u32((next() * 3.0) as u32 % 3).unwrap();
        let alpha = 0.03 + 0.97 * next() * next();
        let rough = if dist == Distribution::BlinnPhong {
            splitray::bsdf::microfacet::blinn_phong_exponent(alpha)
        } else {
            alpha
        };
        let eta = if next() < 0.5 {
            1.1 + next()
        } else {
            1.0 / (1.1 + next())
        };
        let b = match k {
            kind::LAMBERT => Bsdf::Lambert { albedo: rgb },
            kind::OREN_NAYAR => Bsdf::OrenNayar {
                albedo: rgb,
                sigma: next(),
            },
            kind::MIRROR => Bsdf::Mirror { tint: rgb },
            kind::DIELECTRIC => Bsdf::Dielectric { tint: rgb, eta },
            kind::MICROFACET_REFLECTION => Bsdf::MicrofacetReflection {
                f0: rgb,
                distribution: dist,
                roughness: rough,
            },
            _ => Bsdf::MicrofacetDielectric {
                tint: rgb,
                distribution: dist,
                roughness: rough,
                eta,
            },
        };
        b.layer(1.0)
    };
    (0..count)
        .map(|_| {
            if which < kind::COUNT {
                BsdfParams::new(&[layer(which, &mut next)])
            } else {
                let n = 2 + (next() * 3.0) as usize % 3;
                let layers: Vec<BsdfLayer> = (0..n)
                    .map(|_| {
                        let k = (next() * kind::COUNT as f32) as u32 % kind::COUNT;
                        let mut l = layer(k, &mut next);
                        l.tint_weight[3] = 0.05 + next();
                        l
                    })
                    .collect();
                BsdfParams::new(&layers)
            }
        })
        .collect()
}

const KINDS: [(u32, &str); 7] = [
    (kind::LAMBERT, "lambert"),
    (kind::OREN_NAYAR, "oren-nayar"),
    (kind::MIRROR, "mirror"),
    (kind::DIELECTRIC, "dielectric"),
    (kind::MICROFACET_REFLECTION, "microfacet reflection"),
    (kind::MICROFACET_DIELECTRIC, "rough dielectric"),
    (kind::COUNT, "layered"),
];

/// Relative agreement of one GPU/CPU value pair: |g − c| ≤ REL · max(|g|, |c|) + ABS.
const REL: f32 = 1e-4;
const ABS: f32 = 1e-6;

fn agree(g: f32, c: f32) -> bool {
    (g - c).abs() <= REL * g.abs().max(c.abs()) + ABS
}

fn rel_err(g: f32, c: f32) -> f32 {
    (g - c).abs() / (g.abs().max(c.abs()) + ABS / REL)
}

#[test]
fn rust_and_glsl_bsdf_layouts_agree() {
    assert_eq!(std::mem::size_of::<BsdfLayer>(), 32);
    assert_eq!(std::mem::size_of::<BsdfParams>(), 144);
    let gpu = common::gpu();
    let n = 7usize;
    let f = uniforms(n * 40, 5);
    let params: Vec<BsdfParams> = (0..n)
        .map(|i| {
            let mut p = BsdfParams::default();
            for (k, l) in p.layers.iter_mut().enumerate() {
                let b = i * 40 + k * 8;
                *l = BsdfLayer {
                    tint_weight: [f[b], f[b + 1], f[b + 2], f[b + 3]],
                    kind: (i + k) as u32,
                    distribution: (i * 3 + k) as u32,
                    roughness: f[b + 4],
                    ior: f[b + 5],
                };
            }
            p.count = i as u32 + 1;
            p.pad = [i as u32 + 2, i as u32 + 3, i as u32 + 4];
            p
        })
        .collect();
    let keys: Vec<u32> = (0..n)
        .map(|i| {
            material_key(
                MaterialType::from_u8(i as u8).unwrap(),
                0xFF_FFFF - i as u32 * 12345,
            )
        })
        .collect();
    let pipeline = ComputePipeline::new(
        &gpu,
        &PipelineDesc {
            kernel: shaders::BSDF_LAYOUT_ECHO,
            bindings: 3,
            push_constant_bytes: 4,
            spec: &[64],
        },
    )
    .unwrap();
    let pb = gpu.upload("params", &params).unwrap();
    let kb = gpu.upload("keys", &keys).unwrap();
    let out = gpu.zeroed::<f32>("out", n * 38).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(
        &pipeline,
        &[(&pb).into(), (&kb).into(), (&out).into()],
        &(n as u32),
        n as u64,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let fields = out.read::<f32>().unwrap();
    for (i, p) in params.iter().enumerate() {
        let mut want = vec![];
        for l in &p.layers {
            want.extend(l.tint_weight);
            want.extend([l.kind as f32, l.distribution as f32, l.roughness, l.ior]);
        }
        want.push(p.count as f32);
        want.extend(p.pad.map(|x| x as f32));
        want.push(key_type(keys[i]) as f32);
        want.push(key_id(keys[i]) as f32);
        assert_eq!(&fields[i * 38..(i + 1) * 38], &want[..], "record {i}");
    }
    common::assert_clean(&gpu);
}

/// Random query directions: mostly uniform on the sphere, some near grazing.
fn random_dir(u: &[f32]) -> Vec3 {
    let w = uniform_sphere(u[0], u[1]);
    if u[2] < 0.1 {
        // push towards the horizon
        Vec3::new(w.x, w.y, w.z * 0.02).normalize()
    } else {
        w
    }
}

#[test]
fn gpu_eval_and_pdf_match_cpu() {
    let gpu = common::gpu();
    let per_kind = 12_000usize;
    let mut params = vec![];
    let mut queries = vec![];
    for (which, _) in KINDS {
        let base = params.len() as u32;
        params.extend(random_params(which, 64, 100 + which as u64));
        let r = uniforms(per_kind * 8, 200 + which as u64);
        for i in 0..per_kind {
            let c = &r[i * 8..];
            let wo = random_dir(&c[0..3]);
            let mut wi = random_dir(&c[3..6]);
            // half the pairs on the same side (reflection), half opposite
            if (c[6] < 0.5) == (wo.z * wi.z < 0.0) {
                wi.z = -wi.z;
            }
            queries.push(EvalQuery {
                wo: wo.into(),
                params: base + (i % 64) as u32,
                wi: wi.into(),
                mode: (c[7] < 0.5) as u32,
            });
        }
    }
    let results: Vec<[f32; 4]> = run_kernel(&gpu, shaders::BSDF_EVAL_TEST, &params, &queries);
    let mut report = vec![];
    for (ki, (_, name)) in KINDS.iter().enumerate() {
        let (mut worst, mut nonzero, mut bad) = (0.0f32, 0, vec![]);
        for i in ki * per_kind..(ki + 1) * per_kind {
            let q = &queries[i];
            let p = &params[q.params as usize];
            let (wo, wi, mode) = (Vec3::from(q.wo), Vec3::from(q.wi), mode_of(q.mode));
            let f = p.eval(wo, wi, mode);
            let pdf = p.pdf(wo, wi, mode);
            let g = results[i];
            let pairs = [(g[0], f.x), (g[1], f.y), (g[2], f.z), (g[3], pdf)];
            if pdf > 0.0 || f.max_element() > 0.0 {
                nonzero += 1;
            }
            for (gv, cv) in pairs {
                worst = worst.max(rel_err(gv, cv));
                if !agree(gv, cv) && bad.len() < 5 {
                    bad.push(format!(
                        "{p:?} wo {wo} wi {wi} {mode:?}: gpu {g:?} cpu {f} {pdf}"
                    ));
                }
            }
        }
        report.push(format!("{name}: {nonzero} nonzero, worst rel {worst:.2e}"));
        assert!(
            bad.is_empty(),
            "{name}: GPU/CPU eval differ:\n{}",
            bad.join("\n")
        );
        if !matches!(*name, "mirror" | "dielectric") {
            assert!(
                nonzero > per_kind / 4,
                "{name}: too few nonzero evaluations"
            );
        }
    }
    eprintln!("eval: {}", report.join("; "));
    common::assert_clean(&gpu);
}

/// `BSDF_KINDS` (specialization constant 2 of bsdf.glsl): a kernel specialized to the
/// kinds its records use (`layer_kinds`) evaluates them as the general kernel does, and
/// the constant really removes code: a kernel left with Lambert alone evaluates rough
/// dielectrics to nothing.
#[test]
fn kernels_specialized_to_the_kinds_in_use_agree_with_the_general_one() {
    let gpu = common::gpu();
    let queries_of = |params: &[BsdfParams], seed: u64| -> Vec<EvalQuery> {
        let r = uniforms(3000 * 7, seed);
        (0..3000)
            .map(|i| {
                let c = &r[i * 7..];
                EvalQuery {
                    wo: random_dir(&c[0..3]).into(),
                    params: (i % params.len()) as u32,
                    wi: random_dir(&c[3..6]).into(),
                    mode: (c[6] < 0.5) as u32,
                }
            })
            .collect()
    };
    let eval = |params: &[BsdfParams], queries: &[EvalQuery], spec: &[u32]| -> Vec<[f32; 4]> {
        run_specialized(&gpu, shaders::BSDF_EVAL_TEST, params, queries, spec)
    };
    // Stacks of every kind but Oren–Nayar.
    let params: Vec<BsdfParams> = random_params(kind::COUNT, 64, 31)
        .into_iter()
        .filter(|p| {
            p.layers[..p.count as usize]
                .iter()
                .all(|l| l.kind != kind::OREN_NAYAR)
        })
        .collect();
    let kinds = layer_kinds(&params);
    assert_eq!(kinds & (1 << kind::OREN_NAYAR), 0);
    let queries = queries_of(&params, 32);
    let general = eval(&params, &queries, &[64]);
    let special = eval(&params, &queries, &kernel_constants(64, 1, kinds));
    let nonzero = general.iter().filter(|g| g[3] > 0.0).count();
    assert!(nonzero > queries.len() / 4, "{nonzero} nonzero pdfs");
    for (i, (g, s)) in general.iter().zip(&special).enumerate() {
        assert!(
            g.iter().zip(s).all(|(g, s)| agree(*g, *s)),
            "query {i}: general {g:?}, specialized to {kinds:#b} {s:?}"
        );
    }
    let rough = random_params(kind::MICROFACET_DIELECTRIC, 16, 33);
    let queries = queries_of(&rough, 34);
    assert!(eval(&rough, &queries, &[64]).iter().any(|g| g[3] > 0.0));
    let lambert_only = eval(
        &rough,
        &queries,
        &kernel_constants(64, 1, 1 << kind::LAMBERT),
    );
    assert!(lambert_only.iter().all(|g| *g == [0.0; 4]));
    common::assert_clean(&gpu);
}

fn discrete(valid: bool, flags: u32, layer: u32) -> (bool, u32, u32) {
    (
        valid,
        if valid { flags } else { 0 },
        if valid { layer } else { 0 },
    )
}

/// Whether the CPU reaches the GPU's discrete outcome with one random number nudged by
/// ±1e-5: the decision lies within rounding distance of a boundary.
fn near_boundary(
    p: &BsdfParams,
    wo: Vec3,
    u: [f32; 3],
    mode: TransportMode,
    want: (bool, u32, u32),
) -> bool {
    (0..3).any(|k| {
        [-1e-5f32, 1e-5].iter().any(|d| {
            let mut v = u;
            v[k] = (v[k] + d).clamp(0.0, 0.999_999_9);
            let s = p.sample(wo, v, mode);
            let got = match s {
                Some(s) => discrete(true, s.flags.0, s.layer),
                None => discrete(false, 0, 0),
            };
            got == want
        })
    })
}

#[test]
fn gpu_sample_matches_cpu() {
    let gpu = common::gpu();
    let per_kind = 12_000usize;
    let mut params = vec![];
    let mut queries = vec![];
    for (which, _) in KINDS {
        let base = params.len() as u32;
        params.extend(random_params(which, 64, 300 + which as u64));
        let r = uniforms(per_kind * 7, 400 + which as u64);
        for i in 0..per_kind {
            let c = &r[i * 7..];
            let wo = random_dir(&c[0..3]);
            queries.push(SampleQuery {
                wo: wo.into(),
                params: base + (i % 64) as u32,
                u: [c[3], c[4], c[5]],
                mode: (c[6] < 0.5) as u32,
            });
        }
    }
    let results: Vec<SampleResult> = run_kernel(&gpu, shaders::BSDF_SAMPLE_TEST, &params, &queries);
    let mut report = vec![];
    for (ki, (_, name)) in KINDS.iter().enumerate() {
        let (mut worst, mut worst_dir, mut valid, mut boundary) = (0.0f32, 0.0f32, 0, 0);
        let mut bad = vec![];
        for i in ki * per_kind..(ki + 1) * per_kind {
            let q = &queries[i];
            let p = &params[q.params as usize];
            let (wo, mode) = (Vec3::from(q.wo), mode_of(q.mode));
            let g = &results[i];
            let c: Option<BsdfSample> = p.sample(wo, q.u, mode);
            let gd = discrete(g.valid != 0, g.flags, g.layer);
            let cd = match &c {
                Some(s) => discrete(true, s.flags.0, s.layer),
                None => discrete(false, 0, 0),
            };
            if gd != cd {
                if near_boundary(p, wo, q.u, mode, gd) {
                    boundary += 1;
                } else if bad.len() < 5 {
                    bad.push(format!(
                        "{p:?} wo {wo} u {:?} {mode:?}: gpu {g:?} cpu {c:?}",
                        q.u
                    ));
                }
                continue;
            }
            let Some(c) = c else { continue };
            valid += 1;
            let dir_err = (Vec3::from(g.wi) - c.wi).abs().max_element();
            worst_dir = worst_dir.max(dir_err);
            // f and pdf are compared with the CPU's values *at the GPU's direction*: for
            // very peaked lobes (e.g. Blinn–Phong n ≈ 1600 at grazing) the ~1e-5 f32
            // difference between the two sampled directions alone changes f by ~1e-3.
            let (cf, cpdf) = if c.flags.is_specular() {
                (c.f, c.pdf)
            } else {
                let gwi = Vec3::from(g.wi);
                (p.eval(wo, gwi, mode), p.pdf(wo, gwi, mode))
            };
            let c = BsdfSample {
                f: cf,
                pdf: cpdf,
                ..c
            };
            let pairs = [
                (g.f[0], c.f.x),
                (g.f[1], c.f.y),
                (g.f[2], c.f.z),
                (g.pdf, c.pdf),
                (g.eta, c.eta),
            ];
            let values_agree = pairs.iter().all(|&(a, b)| agree(a, b));
            for (a, b) in pairs {
                worst = worst.max(rel_err(a, b));
            }
            if (dir_err > 1e-5 || !values_agree) && bad.len() < 5 {
                let l = &p.layers[c.layer as usize];
                bad.push(format!(
                    "kind {} dist {} rough {} ior {} wo {wo} u {:?} {mode:?}: gpu wi {:?} f {:?} pdf {} | cpu wi {} f {} pdf {}",
                    l.kind, l.distribution, l.roughness, l.ior, q.u, g.wi, g.f, g.pdf, c.wi, c.f, c.pdf
                ));
            }
        }
        report.push(format!(
            "{name}: {valid} valid, worst rel {worst:.2e}, worst |Δwi| {worst_dir:.1e}, {boundary} near-boundary choices"
        ));
        assert!(
            bad.is_empty(),
            "{name}: GPU/CPU samples differ:\n{}",
            bad.join("\n")
        );
        assert!(
            valid > per_kind / 2,
            "{name}: too few valid samples ({valid})"
        );
        assert!(
            boundary * 1000 <= per_kind,
            "{name}: {boundary} near-boundary discrete mismatches (allowed: 0.1%)"
        );
    }
    eprintln!("sample: {}", report.join("; "));
    common::assert_clean(&gpu);
}

#[test]
fn gpu_samples_pass_chi2() {
    let gpu = common::gpu();
    let white = Vec3::ONE;
    let cases: Vec<(&str, BsdfParams, Vec3)> = vec![
        (
            "lambert",
            Bsdf::Lambert { albedo: white }.params(),
            Vec3::new(0.3, 0.2, 0.93),
        ),
        (
            "oren-nayar",
            Bsdf::OrenNayar {
                albedo: white,
                sigma: 0.5,
            }
            .params(),
            Vec3::new(0.8, 0.1, 0.35),
        ),
        (
            "microfacet reflection (GGX)",
            Bsdf::MicrofacetReflection {
                f0: white,
                distribution: Distribution::Ggx,
                roughness: 0.3,
            }
            .params(),
            Vec3::new(0.6, 0.0, 0.8),
        ),
        (
            "microfacet reflection (Blinn–Phong)",
            Bsdf::MicrofacetReflection {
                f0: white,
                distribution: Distribution::BlinnPhong,
                roughness: 30.0,
            }
            .params(),
            Vec3::new(0.0, 0.9, 0.436),
        ),
        (
            "rough dielectric (Beckmann, η 1.5)",
            Bsdf::MicrofacetDielectric {
                tint: white,
                distribution: Distribution::Beckmann,
                roughness: 0.4,
                eta: 1.5,
            }
            .params(),
            Vec3::new(0.5, 0.5, 0.707),
        ),
        (
            "rough dielectric (GGX, η 1/1.5)",
            Bsdf::MicrofacetDielectric {
                tint: white,
                distribution: Distribution::Ggx,
                roughness: 0.2,
                eta: 1.0 / 1.5,
            }
            .params(),
            Vec3::new(0.3, -0.2, 0.932),
        ),
        (
            "layered",
            BsdfParams::layered(&[
                (Bsdf::Lambert { albedo: white }, 0.4),
                (Bsdf::Mirror { tint: white }, 0.2),
                (
                    Bsdf::MicrofacetDielectric {
                        tint: white,
                        distribution: Distribution::Ggx,
                        roughness: 0.3,
                        eta: 1.33,
                    },
                    0.4,
                ),
            ]),
            Vec3::new(0.4, 0.0, 0.917),
        ),
    ];
    let n = 200_000usize;
    let params: Vec<BsdfParams> = cases.iter().map(|c| c.1).collect();
    let r = uniforms(cases.len() * n * 3, 77);
    let queries: Vec<SampleQuery> = (0..cases.len() * n)
        .map(|i| SampleQuery {
            wo: cases[i / n].2.normalize().into(),
            params: (i / n) as u32,
            u: [r[3 * i], r[3 * i + 1], r[3 * i + 2]],
            mode: 0,
        })
        .collect();
    let results: Vec<SampleResult> = run_kernel(&gpu, shaders::BSDF_SAMPLE_TEST, &params, &queries);
    let settings = Chi2Settings::default();
    let alpha = chi2::sidak(0.01, cases.len());
    let mut failures = vec![];
    for (ci, (name, p, wo)) in cases.iter().enumerate() {
        let wo = wo.normalize();
        let dirs = results[ci * n..(ci + 1) * n]
            .iter()
            .map(|s| (s.valid != 0 && s.flags & 16 == 0).then(|| Vec3::from(s.wi).normalize()));
        let observed = chi2::histogram(dirs, &settings);
        let expected = chi2::expected_frequencies(
            &|wi| p.pdf(wo, wi, TransportMode::Radiance) as f64,
            n,
            &settings,
        );
        match chi2::chi2_test(&observed, &expected, n, settings.min_expected) {
            Ok(o) if o.p_value >= alpha => eprintln!("GPU χ² {name}: p = {:.3}", o.p_value),
            Ok(o) => failures.push(format!("{name}: {o:?}")),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    assert!(
        failures.is_empty(),
        "GPU χ² failures:\n{}",
        failures.join("\n")
    );
    common::assert_clean(&gpu);
}

#[test]
fn gpu_frame_and_shading_correction_match_cpu() {
    use splitray::bsdf::{shading_normal_correction, Frame};
    let gpu = common::gpu();
    let n = 4096usize;
    let r = uniforms(n * 8, 55);
    let mut queries: Vec<[f32; 4]> = vec![];
    for i in 0..n {
        let c = &r[i * 8..];
        let ns = uniform_sphere(c[0], c[1]);
        // a geometric normal within ~35° of the shading normal
        let ng = (ns + 0.6 * uniform_sphere(c[2], c[3])).normalize();
        let wo = uniform_sphere(c[4], c[5]);
        let wi = uniform_sphere(c[6], c[7]);
        for v in [wo, wi, ns, ng] {
            queries.push([v.x, v.y, v.z, 0.0]);
        }
    }
    // Exact poles, where the branchless frame switches sign.
    for k in 0..2 {
        let z = if k == 0 { 1.0 } else { -1.0 };
        queries.extend([
            [0.3, 0.4, 0.866, 0.0],
            [0.0, 0.6, 0.8, 0.0],
            [0.0, 0.0, z, 0.0],
            [0.0, 0.0, z, 0.0],
        ]);
    }
    let total = queries.len() / 4;
    let pipeline = ComputePipeline::new(
        &gpu,
        &PipelineDesc {
            kernel: shaders::BSDF_FRAME_TEST,
            bindings: 2,
            push_constant_bytes: 4,
            spec: &[64],
        },
    )
    .unwrap();
    let qb = gpu.upload("queries", &queries).unwrap();
    let rb = gpu.zeroed::<[f32; 4]>("results", total * 4).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(
        &pipeline,
        &[(&qb).into(), (&rb).into()],
        &(total as u32),
        total as u64,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let out = rb.read::<[f32; 4]>().unwrap();
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    for i in 0..total {
        let [wo, wi, ns, ng] = [0, 1, 2, 3].map(|k| v(queries[4 * i + k]));
        let f = Frame::from_normal(ns);
        let o = &out[4 * i..4 * i + 4];
        assert!(
            (v(o[0]) - f.s).abs().max_element() < 1e-5,
            "s of {ns}: {:?} vs {}",
            o[0],
            f.s
        );
        assert!((v(o[1]) - f.t).abs().max_element() < 1e-5, "t of {ns}");
        assert!(
            (v(o[2]) - f.to_local(wo)).abs().max_element() < 1e-5,
            "to_local"
        );
        assert!((v(o[3]) - wo).abs().max_element() < 1e-5, "round trip");
        let rad = shading_normal_correction(wo, wi, ns, ng, TransportMode::Radiance);
        let imp = shading_normal_correction(wo, wi, ns, ng, TransportMode::Importance);
        assert_eq!(o[0][3], rad);
        assert!(
            agree(o[1][3], imp),
            "correction {wo} {wi} {ns} {ng}: {} vs {imp}",
            o[1][3]
        );
    }
    common::assert_clean(&gpu);
}

/// BSDF records at the edges of their parameters: near-mirror roughness (α = 1e-3 and
/// 1e-4, the Blinn–Phong exponent of the same α) for every distribution, reflecting and
/// refracting from both sides; rough and smooth dielectrics of η exactly 1 (no
/// interface); stacks with a layer of weight 0, and with every weight 0; and the other
/// kinds for reference.
fn degenerate_params() -> Vec<(String, BsdfParams)> {
    let tint = Vec3::new(0.9, 0.6, 0.3);
    let mut cases: Vec<(String, BsdfParams)> = vec![];
    for alpha in [1e-3f32, 1e-4] {
        for distribution in [
            Distribution::BlinnPhong,
            Distribution::Beckmann,
            Distribution::Ggx,
        ] {
            let roughness = if distribution == Distribution::BlinnPhong {
                splitray::bsdf::microfacet::blinn_phong_exponent(alpha)
            } else {
                alpha
            };
            let name = format!("{distribution:?} α {alpha}");
            cases.push((
                format!("reflection, {name}"),
                Bsdf::MicrofacetReflection {
                    f0: tint,
                    distribution,
                    roughness,
                }
                .params(),
            ));
            for eta in [1.5, 1.0 / 1.5] {
                cases.push((
                    format!("rough dielectric η {eta}, {name}"),
                    Bsdf::MicrofacetDielectric {
                        tint,
                        distribution,
                        roughness,
                        eta,
                    }
                    .params(),
                ));
            }
        }
    }
    for (distribution, roughness) in [
        (Distribution::Ggx, 0.3),
        (Distribution::Beckmann, 0.05),
        (Distribution::BlinnPhong, 40.0),
    ] {
        cases.push((
            format!("rough dielectric η 1, {distribution:?} {roughness}"),
            Bsdf::MicrofacetDielectric {
                tint,
                distribution,
                roughness,
                eta: 1.0,
            }
            .params(),
        ));
    }
    cases.push((
        "smooth dielectric η 1".into(),
        Bsdf::Dielectric { tint, eta: 1.0 }.params(),
    ));
    let ggx = Bsdf::MicrofacetReflection {
        f0: tint,
        distribution: Distribution::Ggx,
        roughness: 0.2,
    };
    let lambert = Bsdf::Lambert { albedo: tint };
    let mirror = Bsdf::Mirror { tint };
    cases.push((
        "a layer of weight 0 between two".into(),
        BsdfParams::layered(&[(lambert, 0.5), (ggx, 0.0), (mirror, 0.5)]),
    ));
    cases.push((
        "first and last layers of weight 0".into(),
        BsdfParams::layered(&[(mirror, 0.0), (ggx, 0.7), (lambert, 0.0)]),
    ));
    cases.push((
        "every layer of weight 0".into(),
        BsdfParams::layered(&[(lambert, 0.0), (ggx, 0.0)]),
    ));
    for (name, b) in [
        ("lambert", lambert),
        (
            "oren-nayar",
            Bsdf::OrenNayar {
                albedo: tint,
                sigma: 0.4,
            },
        ),
        ("mirror", mirror),
        (
            "smooth dielectric η 1.5",
            Bsdf::Dielectric { tint, eta: 1.5 },
        ),
    ] {
        cases.push((name.into(), b.params()));
    }
    cases
}

/// Outgoing directions at the edges: the normal from both sides, in the tangent plane
/// (z exactly 0, and −0), and two ordinary ones, above and below.
fn degenerate_wo() -> Vec<Vec3> {
    vec![
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::new(0.0, 1.0, -0.0),
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(0.0, -0.6, -0.8),
    ]
}

/// Incident directions that make the half vectors degenerate: −wo (wo + wi = 0, and
/// straight through), wo itself, wo mirrored about the normal, and the poles and a
/// tangent direction.
fn degenerate_wi(wo: Vec3) -> Vec<Vec3> {
    vec![
        -wo,
        wo,
        Vec3::new(-wo.x, -wo.y, wo.z),
        Vec3::Z,
        -Vec3::Z,
        Vec3::new(-1.0, 0.0, 0.0),
    ]
}

/// Eval, pdf and sample on [`degenerate_params`] × [`degenerate_wo`] × (for eval)
/// [`degenerate_wi`] × (for sample) random numbers at 0, ½ and just below 1, both
/// transport modes: the GPU agrees with the CPU as in [`gpu_eval_and_pdf_match_cpu`] and
/// [`gpu_sample_matches_cpu`], and nothing is NaN or infinite — a sample may have pdf 0
/// or no direction, never a NaN weight.
#[test]
fn gpu_eval_and_sample_match_cpu_on_degenerate_inputs() {
    let gpu = common::gpu();
    let cases = degenerate_params();
    let params: Vec<BsdfParams> = cases.iter().map(|c| c.1).collect();
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    let us = [0.0f32, 0.5, splitray::bsdf::sampling::ONE_MINUS_EPSILON];
    let (mut eval_queries, mut sample_queries) = (vec![], vec![]);
    for p in 0..params.len() as u32 {
        for wo in degenerate_wo() {
            for mode in [0, 1] {
                for wi in degenerate_wi(wo) {
                    eval_queries.push(EvalQuery {
                        wo: wo.into(),
                        params: p,
                        wi: wi.into(),
                        mode,
                    });
                }
                for u in us
                    .iter()
                    .flat_map(|&a| us.iter().flat_map(move |&b| us.map(|c| [a, b, c])))
                {
                    sample_queries.push(SampleQuery {
                        wo: wo.into(),
                        params: p,
                        u,
                        mode,
                    });
                }
            }
        }
    }

    let evals: Vec<[f32; 4]> = run_kernel(&gpu, shaders::BSDF_EVAL_TEST, &params, &eval_queries);
    let mut bad = vec![];
    let mut nonzero = 0;
    for (q, g) in eval_queries.iter().zip(&evals) {
        let (name, p) = &cases[q.params as usize];
        let (wo, wi, mode) = (Vec3::from(q.wo), Vec3::from(q.wi), mode_of(q.mode));
        let (f, pdf) = (p.eval(wo, wi, mode), p.pdf(wo, wi, mode));
        let c = [f.x, f.y, f.z, pdf];
        nonzero += (pdf > 0.0) as usize;
        let sound = finite(g) && finite(&c) && g.iter().chain(&c).all(|x| *x >= 0.0);
        if (!sound || !g.iter().zip(&c).all(|(g, c)| agree(*g, *c))) && bad.len() < 8 {
            bad.push(format!(
                "{name} wo {wo} wi {wi} {mode:?}: gpu {g:?} cpu {c:?}"
            ));
        }
    }
    assert!(
        bad.is_empty(),
        "eval on degenerate inputs:\n{}",
        bad.join("\n")
    );
    assert!(nonzero > eval_queries.len() / 10, "{nonzero} nonzero pdfs");

    let samples: Vec<SampleResult> =
        run_kernel(&gpu, shaders::BSDF_SAMPLE_TEST, &params, &sample_queries);
    let mut valid = 0;
    for (q, g) in sample_queries.iter().zip(&samples) {
        let (name, p) = &cases[q.params as usize];
        let (wo, mode) = (Vec3::from(q.wo), mode_of(q.mode));
        let c = p.sample(wo, q.u, mode);
        let what = format!("{name} wo {wo} u {:?} {mode:?}: gpu {g:?} cpu {c:?}", q.u);
        let gd = discrete(g.valid != 0, g.flags, g.layer);
        let cd = match &c {
            Some(s) => discrete(true, s.flags.0, s.layer),
            None => discrete(false, 0, 0),
        };
        if gd != cd {
            bad.push(what);
            continue;
        }
        let gf = [g.f[0], g.f[1], g.f[2], g.pdf, g.eta];
        let Some(c) = c else {
            // No sample: whatever the record holds must still be harmless.
            if !finite(&gf) || !finite(&g.wi) {
                bad.push(format!("not finite: {what}"));
            }
            continue;
        };
        valid += 1;
        let cf = [c.f.x, c.f.y, c.f.z, c.pdf, c.eta];
        let sound = finite(&gf)
            && finite(&cf)
            && finite(&g.wi)
            && gf[..4].iter().chain(&cf[..4]).all(|x| *x >= 0.0);
        if !sound {
            bad.push(format!("not finite: {what}"));
            continue;
        }
        let dir_err = (Vec3::from(g.wi) - c.wi).abs().max_element();
        // As in gpu_sample_matches_cpu: a glossy sample's f and pdf are compared with the
        // CPU's at the GPU's direction, since a peaked lobe turns the rounding of the
        // direction into large changes of f.
        let (cf, cpdf) = if c.flags.is_specular() {
            (c.f, c.pdf)
        } else {
            let gwi = Vec3::from(g.wi);
            (p.eval(wo, gwi, mode), p.pdf(wo, gwi, mode))
        };
        let pairs = [
            (g.f[0], cf.x),
            (g.f[1], cf.y),
            (g.f[2], cf.z),
            (g.pdf, cpdf),
            (g.eta, c.eta),
        ];
        if dir_err > 1e-5 || !pairs.iter().all(|&(a, b)| agree(a, b)) {
            bad.push(format!("|Δwi| {dir_err:.1e}: {what}"));
        }
    }
    bad.truncate(8);
    assert!(
        bad.is_empty(),
        "samples on degenerate inputs:\n{}",
        bad.join("\n")
    );
    assert!(valid > sample_queries.len() / 10, "{valid} valid samples");

    // η exactly 1 is no interface: whatever the roughness, light goes straight through
    // with its tint, a delta lobe (eval and pdf 0) that every sample takes, on the GPU
    // as on the CPU; the microfacet half vector wi + wo would be a rounding residue.
    let index_matched = |name: &str| name.contains("η 1,") || name.ends_with("η 1");
    for (q, g) in eval_queries.iter().zip(&evals) {
        let name = &cases[q.params as usize].0;
        if index_matched(name) {
            assert_eq!(*g, [0.0; 4], "{name}: eval {q:?}");
        }
    }
    let mut through = 0;
    for (q, g) in sample_queries.iter().zip(&samples) {
        let (name, p) = &cases[q.params as usize];
        let wo = Vec3::from(q.wo);
        if !index_matched(name) || wo.z == 0.0 {
            continue;
        }
        let c = p.sample(wo, q.u, mode_of(q.mode));
        let c = c.unwrap_or_else(|| panic!("{name}: no sample for {q:?}"));
        let tint = Vec3::from_slice(&p.layers[0].tint_weight[..3]);
        assert_eq!(
            c.flags,
            BsdfFlags::TRANSMISSION | BsdfFlags::SPECULAR,
            "{name}: {q:?}"
        );
        assert_eq!((c.wi, c.eta), (-wo, 1.0), "{name}: {q:?}");
        let weight = c.f * c.wi.z.abs() / c.pdf;
        assert!(
            (weight - tint).abs().max_element() < 1e-6,
            "{name}: weight {weight}"
        );
        assert_eq!(g.valid, 1, "{name}: GPU {q:?}");
        let gpu_sample = (Vec3::from(g.wi), g.eta, g.flags);
        assert_eq!(gpu_sample, (-wo, 1.0, c.flags.0), "{name}: GPU {q:?}");
        through += 1;
    }
    assert!(through > 0);
    common::assert_clean(&gpu);
}
