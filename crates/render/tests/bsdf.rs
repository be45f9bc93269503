//! The BSDF samplers against their pdfs: a chi-square goodness-of-fit test of sampled
//! directions against the histogram the pdf predicts (the test Mitsuba 3 runs on its samplers,
//! `mitsuba/python/chi2.py`: a (cos θ, φ) grid over the sphere, expected counts by integrating
//! the pdf over each cell, cells expecting fewer than 5 samples pooled, Šidák-corrected
//! significance 1%), plus the invariants of `parallax_render::bsdf` (weight = eval / pdf,
//! pdf(sample) = pdf(), reciprocity, energy) and the discrete lobe probabilities of the delta
//! models.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use parallax_core::sampling::Rng;
use parallax_render::brdf::fresnel_dielectric;
use parallax_render::bsdf::specular::thin_dielectric_reflectance;
use parallax_render::bsdf::{Bsdf, MetallicRoughness};

/// Grid of the chi-square test: cos θ in [-1, 1] x φ in [0, 2π).
const THETA_BINS: usize = 32;
const PHI_BINS: usize = 64;
/// Midpoint sub-samples per cell edge when integrating the pdf.
const SUB: usize = 12;
const SAMPLES: usize = 400_000;

fn dir(cos_t: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos_t)
}

fn cell_of(w: Vec3) -> usize {
    let t = (((w.z + 1.0) * 0.5) * THETA_BINS as f32).floor() as isize;
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let p = (phi / (2.0 * PI) * PHI_BINS as f32).floor() as isize;
    let t = t.clamp(0, THETA_BINS as isize - 1) as usize;
    let p = p.clamp(0, PHI_BINS as isize - 1) as usize;
    t * PHI_BINS + p
}

/// `ln Γ(x)` (Lanczos, g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma `Q(a, x)` (series below `a + 1`, Lentz continued
/// fraction above; Numerical Recipes §6.2). Hand-written: a statistics crate would pull a
/// linear-algebra stack into the test build for one function.
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let lg = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut del, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - lg).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - lg).exp() * h
    }
}

/// The p-value of the chi-square test of `bsdf`'s sampler for `wo`, and the integral of its
/// pdf over the sphere.
fn chi2_p_value(bsdf: &Bsdf, wo: Vec3, seed: u64) -> (f64, f64) {
    let cells = THETA_BINS * PHI_BINS;
    let mut observed = vec![0.0f64; cells];
    let mut rng = Rng::new(seed, 7);
    for _ in 0..SAMPLES {
        let u_lobe = rng.next_f32();
        let u = rng.next_vec2();
        if let Some(s) = bsdf.sample(wo, u_lobe, u) {
            assert!(!s.delta);
            observed[cell_of(s.wi)] += 1.0;
        }
    }
    let mut expected = vec![0.0f64; cells];
    let dc = 2.0 / THETA_BINS as f64;
    let dp = 2.0 * std::f64::consts::PI / PHI_BINS as f64;
    for t in 0..THETA_BINS {
        for p in 0..PHI_BINS {
            let mut sum = 0.0f64;
            for i in 0..SUB {
                for j in 0..SUB {
                    let c = -1.0 + (t as f64 + (i as f64 + 0.5) / SUB as f64) * dc;
                    let ph = (p as f64 + (j as f64 + 0.5) / SUB as f64) * dp;
                    sum += bsdf.pdf(wo, dir(c as f32, ph as f32)) as f64;
                }
            }
            expected[t * PHI_BINS + p] = sum * dc * dp / (SUB * SUB) as f64;
        }
    }
    let integral: f64 = expected.iter().sum();
    // Pool the cells that expect fewer than 5 samples (Mitsuba's rule).
    let (mut chi2, mut dof) = (0.0f64, 0i64);
    let (mut pool_obs, mut pool_exp) = (0.0f64, 0.0f64);
    for (o, e) in observed.iter().zip(&expected) {
        let e = e * SAMPLES as f64;
        if e < 5.0 {
            pool_obs += o;
            pool_exp += e;
        } else {
            chi2 += (o - e).powi(2) / e;
            dof += 1;
        }
    }
    if pool_exp >= 5.0 {
        chi2 += (pool_obs - pool_exp).powi(2) / pool_exp;
        dof += 1;
    } else {
        assert!(
            pool_obs <= 5.0 + 5.0 * pool_exp,
            "{pool_obs} samples where the pdf expects {pool_exp}"
        );
    }
    dof -= 1;
    assert!(dof > 10, "too few cells ({dof}) for a meaningful test");
    (gamma_q(dof as f64 / 2.0, chi2 / 2.0), integral)
}

fn smooth_cases() -> Vec<(String, Bsdf)> {
    let mut v = vec![(
        "lambert".to_string(),
        Bsdf::Lambert {
            albedo: Vec3::new(0.8, 0.5, 0.2),
        },
    )];
    for (metallic, roughness) in [(0.0, 1.0), (0.0, 0.5), (1.0, 0.5), (0.5, 0.3), (1.0, 0.3)] {
        v.push((
            format!("metallic-roughness m={metallic} r={roughness}"),
            Bsdf::MetallicRoughness(MetallicRoughness::new(
                Vec3::new(0.9, 0.6, 0.3),
                metallic,
                roughness,
            )),
        ));
    }
    v
}

fn wo_cases() -> [Vec3; 3] {
    [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.5, 0.2, 0.8).normalize(),
        Vec3::new(-0.9, 0.3, 0.12).normalize(),
    ]
}

#[test]
fn chi_square_of_every_smooth_sampler_against_its_pdf() {
    let cases = smooth_cases();
    let tests = cases.len() * wo_cases().len();
    // Šidák correction: the whole suite fails by chance with probability 1%.
    let alpha = 1.0 - 0.99f64.powf(1.0 / tests as f64);
    let mut seed = 1;
    for (name, bsdf) in &cases {
        for wo in wo_cases() {
            seed += 1;
            let (p, integral) = chi2_p_value(bsdf, wo, seed);
            assert!(
                p > alpha,
                "{name}, wo {wo}: chi-square p-value {p:.2e} <= {alpha:.2e}"
            );
            assert!(
                integral <= 1.0 + 2e-3 && integral > 0.5,
                "{name}, wo {wo}: pdf integrates to {integral}"
            );
        }
    }
}

#[test]
fn the_chi_square_test_rejects_a_wrong_pdf() {
    // A sampler whose pdf is off (GGX sampled at roughness 0.5, pdf claimed at 0.6) must fail:
    // the test can fail.
    struct Wrong(MetallicRoughness, MetallicRoughness);
    let a = MetallicRoughness::new(Vec3::splat(0.5), 1.0, 0.5);
    let b = MetallicRoughness::new(Vec3::splat(0.5), 1.0, 0.6);
    let w = Wrong(a, b);
    let wo = Vec3::new(0.3, 0.0, 0.95).normalize();
    // Histogram of a's sampler against b's pdf.
    let cells = THETA_BINS * PHI_BINS;
    let mut observed = vec![0.0f64; cells];
    let mut rng = Rng::new(3, 7);
    for _ in 0..SAMPLES {
        if let Some(s) = w.0.sample(wo, rng.next_f32(), rng.next_vec2()) {
            observed[cell_of(s.wi)] += 1.0;
        }
    }
    let (mut chi2, mut dof) = (0.0, 0);
    for (k, o) in observed.iter().enumerate() {
        let (t, p) = (k / PHI_BINS, k % PHI_BINS);
        let c = -1.0 + (t as f32 + 0.5) * 2.0 / THETA_BINS as f32;
        let ph = (p as f32 + 0.5) * 2.0 * PI / PHI_BINS as f32;
        let e = w.1.pdf(wo, dir(c, ph)) as f64
            * (2.0 / THETA_BINS as f64)
            * (2.0 * std::f64::consts::PI / PHI_BINS as f64)
            * SAMPLES as f64;
        if e >= 5.0 {
            chi2 += (o - e).powi(2) / e;
            dof += 1;
        }
    }
    let p = gamma_q((dof - 1) as f64 / 2.0, chi2 / 2.0);
    assert!(p < 1e-6, "a wrong pdf passed with p = {p}");
}

#[test]
fn gamma_q_matches_known_chi_square_quantiles() {
    // chi-square 95% quantiles: dof 1 -> 3.841, dof 10 -> 18.307, dof 100 -> 124.342.
    for (dof, x) in [(1.0, 3.841_458_8), (10.0, 18.307_038), (100.0, 124.342_13)] {
        let q = gamma_q(dof / 2.0, x / 2.0);
        assert!((q - 0.05).abs() < 1e-5, "dof {dof}: Q = {q}");
    }
}

#[test]
fn smooth_samples_weigh_eval_over_pdf_and_conserve_energy() {
    let mut rng = Rng::new(11, 3);
    for (name, bsdf) in smooth_cases() {
        for wo in wo_cases() {
            let n = 100_000;
            let mut albedo = Vec3::ZERO;
            for _ in 0..n {
                let Some(s) = bsdf.sample(wo, rng.next_f32(), rng.next_vec2()) else {
                    continue;
                };
                let pdf = bsdf.pdf(wo, s.wi);
                let f = bsdf.eval(wo, s.wi);
                assert!((s.pdf - pdf).abs() <= 1e-4 * pdf.max(1.0), "{name}");
                let expect = f / pdf;
                assert!(
                    (s.weight - expect).abs().max_element() <= 1e-4 * expect.max_element().max(1.0),
                    "{name}: weight {} vs eval/pdf {expect}",
                    s.weight
                );
                assert!(s.weight.min_element() >= 0.0 && s.weight.is_finite());
                albedo += s.weight;
            }
            let albedo = albedo / n as f32;
            assert!(
                albedo.max_element() <= 1.0 + 1e-2,
                "{name}, wo {wo}: directional albedo {albedo} exceeds 1"
            );
        }
    }
}

#[test]
fn smooth_models_are_reciprocal() {
    let mut rng = Rng::new(5, 5);
    for (name, bsdf) in smooth_cases() {
        for _ in 0..1000 {
            let a = parallax_core::sampling::warp::uniform_hemisphere(rng.next_vec2());
            let b = parallax_core::sampling::warp::uniform_hemisphere(rng.next_vec2());
            if a.z < 1e-3 || b.z < 1e-3 {
                continue;
            }
            let fab = bsdf.eval(a, b) / b.z;
            let fba = bsdf.eval(b, a) / a.z;
            assert!(
                (fab - fba).abs().max_element() <= 1e-3 * fab.max_element().max(1e-3),
                "{name}: f({a}, {b}) = {fab} but f({b}, {a}) = {fba}"
            );
        }
    }
}

/// Fraction of reflections out of `n` samples of a delta model.
fn reflected_fraction(bsdf: &Bsdf, wo: Vec3, n: usize) -> f64 {
    let mut rng = Rng::new(9, 1);
    let mut refl = 0usize;
    for _ in 0..n {
        let s = bsdf.sample(wo, rng.next_f32(), Vec2::ZERO).unwrap();
        assert!(s.delta && s.weight.is_finite());
        if s.wi.z > 0.0 {
            assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-5);
            refl += 1;
        }
    }
    refl as f64 / n as f64
}

#[test]
fn delta_lobes_are_chosen_by_their_fresnel_energy() {
    let n = 200_000;
    // 5 standard deviations of a binomial proportion.
    let tol = |p: f64| 5.0 * (p * (1.0 - p) / n as f64).sqrt() + 1e-9;
    for cos in [1.0f32, 0.6, 0.2] {
        let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
        for eta in [1.5f32, 1.0 / 1.5] {
            let f = fresnel_dielectric(cos, eta) as f64;
            let got = reflected_fraction(&Bsdf::Dielectric { eta }, wo, n);
            assert!(
                (got - f).abs() <= tol(f),
                "eta {eta} cos {cos}: {got} vs F {f}"
            );
            if f < 1.0 {
                // Snell's law on a refracted sample.
                let s = Bsdf::Dielectric { eta }
                    .sample(wo, 0.999_999, Vec2::ZERO)
                    .unwrap();
                let sin_t = (1.0 - s.wi.z * s.wi.z).sqrt();
                assert!((wo.x - eta * sin_t).abs() < 1e-4 && s.wi.z < 0.0);
                assert!((s.weight.x - 1.0 / (eta * eta)).abs() < 1e-6 && s.eta == eta);
            }
        }
        let r = thin_dielectric_reflectance(1.5, cos) as f64;
        let got = reflected_fraction(&Bsdf::ThinDielectric { ior: 1.5 }, wo, n);
        assert!((got - r).abs() <= tol(r), "thin cos {cos}: {got} vs R' {r}");
        // Transmission goes straight through.
        let t = Bsdf::ThinDielectric { ior: 1.5 }
            .sample(wo, 0.999_999, Vec2::ZERO)
            .unwrap();
        assert_eq!(t.wi, -wo);
        let m = Bsdf::Mirror {
            tint: Vec3::splat(0.5),
        }
        .sample(wo, 0.3, Vec2::ZERO)
        .unwrap();
        assert_eq!(m.weight, Vec3::splat(0.5));
    }
    // Normal incidence on glass: R = 0.04, the slab reflects 2R / (1 + R).
    assert!((thin_dielectric_reflectance(1.5, 1.0) - 0.08 / 1.04).abs() < 1e-5);
}
