//! Statistical checks of the warps in `parallax_core::sampling::warp`:
//! every pdf integrates to 1 over its domain (quasi-Monte Carlo over the sphere), and the
//! samples follow their pdf (Pearson chi-square on a (θ, φ) histogram against the pdf
//! integrated over each bin, as in Mitsuba's `chi2` test harness).

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use parallax_core::sampling::{
    Ggx, Rng, UNIFORM_HEMISPHERE_PDF, UNIFORM_SPHERE_PDF, cosine_hemisphere, cosine_hemisphere_pdf,
    phong_lobe, phong_lobe_pdf, reflect, sobol_2d, uniform_hemisphere, uniform_sphere,
    uniform_triangle,
};

/// `∫_{S²} f(ω) dω`, estimated with 2^18 scrambled-Sobol directions.
fn integrate_sphere(f: impl Fn(Vec3) -> f32) -> f64 {
    let n = 1u32 << 18;
    let sum: f64 = (0..n)
        .map(|i| f(uniform_sphere(sobol_2d(i, 17))) as f64)
        .sum();
    sum / n as f64 / UNIFORM_SPHERE_PDF as f64
}

const THETA_BINS: usize = 24;
const PHI_BINS: usize = 24;

fn bin_of(w: Vec3) -> usize {
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let t = ((theta / PI) * THETA_BINS as f32).min(THETA_BINS as f32 - 1.0) as usize;
    let p = ((phi / (2.0 * PI)) * PHI_BINS as f32).min(PHI_BINS as f32 - 1.0) as usize;
    t * PHI_BINS + p
}

/// Sub-cells per bin side for the expected counts (12 biased the peaky grazing GGX lobes).
const SUB: usize = 24;

/// Per bin: the SUB x SUB midpoint directions and their `sin θ`, computed once.
fn quadrature_grid() -> &'static [Vec<(Vec3, f32)>] {
    static GRID: OnceLock<Vec<Vec<(Vec3, f32)>>> = OnceLock::new();
    GRID.get_or_init(|| {
        let (dt, dp) = (PI / THETA_BINS as f32, 2.0 * PI / PHI_BINS as f32);
        let mut bins = Vec::with_capacity(THETA_BINS * PHI_BINS);
        for t in 0..THETA_BINS {
            for p in 0..PHI_BINS {
                let mut nodes = Vec::with_capacity(SUB * SUB);
                for i in 0..SUB {
                    for j in 0..SUB {
                        let theta = (t as f32 + (i as f32 + 0.5) / SUB as f32) * dt;
                        let phi = (p as f32 + (j as f32 + 0.5) / SUB as f32) * dp;
                        let (st, ct) = theta.sin_cos();
                        nodes.push((Vec3::new(st * phi.cos(), st * phi.sin(), ct), st));
                    }
                }
                bins.push(nodes);
            }
        }
        bins
    })
}

/// Pearson chi-square of `n` samples against `pdf` on a 24 x 24 (θ, φ) grid. Bins with an
/// expected count below 5 are pooled. Returns (statistic, degrees of freedom).
fn chi2(sample: impl Fn(Vec2) -> Vec3, pdf: impl Fn(Vec3) -> f32, n: u32) -> (f64, usize) {
    let mut observed = vec![0f64; THETA_BINS * PHI_BINS];
    let mut rng = Rng::new(2024, 7);
    for _ in 0..n {
        let w = sample(rng.next_vec2());
        assert!(w.is_finite(), "non-finite sample");
        observed[bin_of(w)] += 1.0;
    }
    // Expected counts: midpoint rule on SUB x SUB sub-cells per bin, dω = sinθ dθ dφ.
    let (dt, dp) = (PI / THETA_BINS as f32, 2.0 * PI / PHI_BINS as f32);
    let cell = (dt * dp) as f64 / (SUB * SUB) as f64 * n as f64;
    let expected: Vec<f64> = quadrature_grid()
        .iter()
        .map(|nodes| {
            nodes
                .iter()
                .map(|&(w, st)| (pdf(w) * st) as f64)
                .sum::<f64>()
                * cell
        })
        .collect();
    let (mut stat, mut dof) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e).powi(2) / e;
            dof += 1;
        }
    }
    if pool_e >= 5.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e;
        dof += 1;
    } else {
        // Samples in bins the pdf says are (almost) empty are a failure on their own.
        assert!(
            pool_o <= 5.0 + 3.0 * pool_e,
            "{pool_o} samples where pdf expects {pool_e}"
        );
    }
    (stat, dof.saturating_sub(1))
}

/// Accept when the statistic is within 6 standard deviations of its mean (`dof`, sd
/// `√(2 dof)`): seeded, so deterministic; a wrong pdf or sampler gives thousands.
fn assert_chi2(name: &str, (stat, dof): (f64, usize)) {
    let limit = dof as f64 + 6.0 * (2.0 * dof as f64).sqrt();
    assert!(
        stat < limit,
        "{name}: chi2 = {stat:.1} with {dof} dof (limit {limit:.1})"
    );
}

fn test_directions() -> [Vec3; 4] {
    [
        Vec3::Z,
        Vec3::new(0.3, 0.2, 0.9).normalize(),
        Vec3::new(-0.7, 0.1, 0.5).normalize(),
        Vec3::new(0.2, -0.95, 0.1).normalize(),
    ]
}

fn ggx_variants() -> [Ggx; 3] {
    [
        Ggx::isotropic(0.3),
        Ggx::isotropic(0.7),
        Ggx::anisotropic(0.2, 0.5),
    ]
}

#[test]
fn pdfs_integrate_to_one() {
    let one = |name: &str, v: f64, tol: f64| {
        assert!((v - 1.0).abs() < tol, "{name}: integral = {v}");
    };
    one(
        "cosine",
        integrate_sphere(|w| cosine_hemisphere_pdf(w.z)),
        2e-3,
    );
    one(
        "hemisphere",
        integrate_sphere(|w| {
            if w.z >= 0.0 {
                UNIFORM_HEMISPHERE_PDF
            } else {
                0.0
            }
        }),
        2e-3,
    );
    for n in [1.0, 10.0, 100.0] {
        one("phong", integrate_sphere(|w| phong_lobe_pdf(w.z, n)), 1e-2);
    }
    for ggx in ggx_variants() {
        // The NDF's projected area is 1: ∫ D(h) cos θ_h dω = 1.
        one(
            "ggx D cos",
            integrate_sphere(|h| ggx.d(h) * h.z.max(0.0)),
            1e-2,
        );
        for wo in test_directions() {
            // Visible normals: ∫ G1(wo) max(0, wo·h) D(h) / wo.z dω = 1 (this checks Λ too).
            one(
                "ggx vndf",
                integrate_sphere(|h| ggx.pdf_visible(wo, h)),
                1e-2,
            );
            // Reflected directions, including those below the horizon: the Jacobian 1/(4 wo·h).
            one(
                "ggx reflect",
                integrate_sphere(|wi| ggx.pdf_reflect(wo, wi)),
                1e-2,
            );
        }
    }
    // The check can fail: a pdf missing its normalisation does not integrate to 1.
    let wrong = integrate_sphere(|w| w.z.max(0.0));
    assert!((wrong - 1.0).abs() > 0.5);
}

#[test]
fn samples_follow_their_pdfs() {
    let n = 200_000;
    assert_chi2(
        "cosine",
        chi2(cosine_hemisphere, |w| cosine_hemisphere_pdf(w.z), n),
    );
    assert_chi2("sphere", chi2(uniform_sphere, |_| UNIFORM_SPHERE_PDF, n));
    let hemi = |w: Vec3| {
        if w.z >= 0.0 {
            UNIFORM_HEMISPHERE_PDF
        } else {
            0.0
        }
    };
    assert_chi2("hemisphere", chi2(uniform_hemisphere, hemi, n));
    for e in [3.0, 30.0] {
        assert_chi2(
            "phong",
            chi2(|u| phong_lobe(u, e), |w| phong_lobe_pdf(w.z, e), n),
        );
    }
    for ggx in ggx_variants() {
        for wo in test_directions() {
            let name = format!("ggx vndf {ggx:?} {wo}");
            let stat = chi2(|u| ggx.sample_visible(wo, u), |h| ggx.pdf_visible(wo, h), n);
            assert_chi2(&name, stat);
            let name = format!("ggx reflect {ggx:?} {wo}");
            let stat = chi2(
                |u| reflect(wo, ggx.sample_visible(wo, u)),
                |wi| ggx.pdf_reflect(wo, wi),
                n,
            );
            assert_chi2(&name, stat);
        }
    }
}

#[test]
fn chi2_rejects_a_mismatched_pdf() {
    // Cosine samples checked against the uniform-hemisphere pdf must fail.
    let hemi = |w: Vec3| {
        if w.z >= 0.0 {
            UNIFORM_HEMISPHERE_PDF
        } else {
            0.0
        }
    };
    let (stat, dof) = chi2(cosine_hemisphere, hemi, 200_000);
    assert!(stat > 10.0 * dof as f64, "chi2 = {stat}");
    // GGX samples against a slightly different roughness must fail as well.
    let (a, b) = (Ggx::isotropic(0.3), Ggx::isotropic(0.36));
    let (stat, dof) = chi2(
        |u| a.sample_visible(Vec3::Z, u),
        |h| b.pdf_visible(Vec3::Z, h),
        200_000,
    );
    assert!(stat > 2.0 * dof as f64, "chi2 = {stat}");
}

#[test]
fn uniform_triangle_fills_sub_triangles_evenly() {
    // Split the triangle at its edge midpoints into 4 congruent sub-triangles: each must get
    // a quarter of the samples (chi-square, 3 dof, limit far in the tail).
    let mut counts = [0f64; 4];
    let mut rng = Rng::new(9, 9);
    let n = 100_000;
    for _ in 0..n {
        let b = uniform_triangle(rng.next_vec2());
        let k = if b.x > 0.5 {
            0
        } else if b.y > 0.5 {
            1
        } else if b.z > 0.5 {
            2
        } else {
            3
        };
        counts[k] += 1.0;
    }
    let e = n as f64 / 4.0;
    let stat: f64 = counts.iter().map(|c| (c - e).powi(2) / e).sum();
    assert!(stat < 30.0, "counts {counts:?}");
}
