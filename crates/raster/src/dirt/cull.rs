//! The cube faces' outcode cull of a triangle, all faces at once (DIRT §4.1.1, the geometry
//! stage that drops a primitive outside a view before it reaches the fragment shader).
//!
//! [`ViewXf::setup`](super::setup::ViewXf::setup) drops a triangle whose three corners are all
//! outside one of a view's five clip planes (the near plane and the four guard planes). A
//! triangle is seen by one or two of the six cube faces around the eye, so most of its six
//! face set-ups end there, each after picking its camera-space corners (signed components of
//! the offsets from the eye) and testing them. [`FaceCull`] makes that decision for every
//! face of the group (views whose rotation rows are signed axes and which share the eye, the
//! near plane and the guard slopes) once per triangle, and the setup runs only for the faces
//! it keeps.
//!
//! **Same decision.** For each face and corner the cull computes the very operations of the
//! setup's outcodes: `q = (s_x d[i_x], s_y d[i_y], s_z d[i_z])` (a product by `±1`), the near
//! plane `-q.z - near`, the guard planes `q.x + a_lo q.z`, `-q.x - a_hi q.z`, `q.y + b_lo q.z`,
//! `-q.y - b_hi q.z` (a product, then a sum or difference, no fused multiply-add) and the test
//! `!(x >= 0)`; a face is dropped when one plane has all three corners outside, which is
//! exactly when the setup returns `None` from its outcodes. The AVX2 version evaluates four
//! faces in the lanes of a vector (each lane's components picked by a permutation, the last
//! face repeated to fill the second vector), the corners one after another;
//! [`FaceCull::keep_portable`] is its scalar twin, and the tests check both against the setup
//! itself.

use super::setup::ViewXf;

/// Most views a group can hold (the lanes of two AVX vectors).
const MAX_GROUP: usize = 8;

/// One face of the group: its view index and, for the camera-space `x`, `y`, `z`, the
/// component of the offset from the eye and its sign.
#[derive(Clone, Copy, Debug)]
struct Face {
    view: usize,
    pick: [(usize, f64); 3],
}

/// The outcode cull of a group of axis views with one eye (module docs).
pub(super) struct FaceCull {
    faces: Vec<Face>,
    /// `[a_lo, a_hi, b_lo, b_hi]`: the guard planes' slopes, shared by the group.
    slopes: [f64; 4],
    near: f64,
    /// Bits of the group's views (view `k` = bit `k`; consecutive views).
    members: u32,
    /// The AVX2 lanes: per vector of four faces (the last face repeated to fill it), the
    /// `f32` pair indices of the picked component and its sign, for `x`, `y`, `z`.
    lanes: [[([i32; 8], [f64; 4]); 3]; 2],
    avx2: bool,
}

impl FaceCull {
    /// The group of `views` (at least two views with signed-axis rotations, the eye, near
    /// plane and slopes of the first such view), or `None` when there is no such group.
    pub fn new(views: &[ViewXf]) -> Option<FaceCull> {
        if views.len() > 32 {
            return None;
        }
        let first = views.iter().find(|v| v.axes().is_some())?;
        let faces: Vec<Face> = views
            .iter()
            .enumerate()
            .filter(|(_, v)| v.shares_cull_with(first))
            .map(|(view, v)| Face {
                view,
                pick: v.axes().expect("axis view"),
            })
            .collect();
        let consecutive = faces
            .iter()
            .zip(&faces[1..])
            .all(|(a, b)| b.view == a.view + 1);
        if faces.len() < 2 || faces.len() > MAX_GROUP || !consecutive {
            return None;
        }
        let members = faces.iter().fold(0, |m, f| m | 1 << f.view);
        let mut lanes = [[([0i32; 8], [0.0f64; 4]); 3]; 2];
        for (v, vector) in lanes.iter_mut().enumerate() {
            for (c, (idx, sign)) in vector.iter_mut().enumerate() {
                for l in 0..4 {
                    let f = &faces[(4 * v + l).min(faces.len() - 1)];
                    let (k, s) = f.pick[c];
                    idx[2 * l] = 2 * k as i32;
                    idx[2 * l + 1] = 2 * k as i32 + 1;
                    sign[l] = s;
                }
            }
        }
        Some(FaceCull {
            faces,
            slopes: first.slopes(),
            near: first.near(),
            members,
            lanes,
            avx2: avx2_available(),
        })
    }

    /// Bits of the views in the group.
    pub fn members(&self) -> u32 {
        self.members
    }

    /// The view at which the kept mask is computed (the group's first; its offsets `d` from
    /// the eye are every member's).
    pub fn first_view(&self) -> usize {
        self.faces[0].view
    }

    /// Bits of the group's views whose setup does not cull the triangle with corner offsets
    /// `d` from the eye by its outcodes (module docs).
    #[inline(always)]
    pub fn keep(&self, d: &[[f64; 3]; 3]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when the CPU has AVX2 (`avx2_available`).
            return unsafe { self.keep_avx2(d) };
        }
        self.keep_portable(d)
    }

    /// [`Self::keep`] in scalar code (the setup's operations, face by face).
    pub fn keep_portable(&self, d: &[[f64; 3]; 3]) -> u32 {
        let [a_lo, a_hi, b_lo, b_hi] = self.slopes;
        let out = |x: f64| (!(x >= 0.0)) as u32;
        let mut keep = 0;
        for f in &self.faces {
            let mut all = 0b11111;
            for c in d {
                let [(ix, sx), (iy, sy), (iz, sz)] = f.pick;
                let (x, y, z) = (sx * c[ix], sy * c[iy], sz * c[iz]);
                all &= out(-z - self.near)
                    | out(x + a_lo * z) << 1
                    | out(-x - a_hi * z) << 2
                    | out(y + b_lo * z) << 3
                    | out(-y - b_hi * z) << 4;
            }
            if all == 0 {
                keep |= 1 << f.view;
            }
        }
        keep
    }

    /// [`Self::keep`] with the faces in AVX2 lanes (four per vector, the corners one after
    /// another; no closures: every intrinsic is compiled with this function's features).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn keep_avx2(&self, d: &[[f64; 3]; 3]) -> u32 {
        use std::arch::x86_64::*;
        let [a_lo, a_hi, b_lo, b_hi] = self.slopes;
        let (a_lo, a_hi) = (_mm256_set1_pd(a_lo), _mm256_set1_pd(a_hi));
        let (b_lo, b_hi) = (_mm256_set1_pd(b_lo), _mm256_set1_pd(b_hi));
        let near = _mm256_set1_pd(self.near);
        let neg = _mm256_set1_pd(-0.0);
        let zero = _mm256_setzero_pd();
        let mut culled = 0;
        for (v, lanes) in self.lanes.iter().enumerate() {
            if 4 * v >= self.faces.len() {
                break;
            }
            // Per plane: the lanes (faces) with every corner so far outside it.
            let mut all = [_mm256_castsi256_pd(_mm256_set1_epi64x(-1)); 5];
            for c in d {
                let src = _mm256_castpd_ps(_mm256_setr_pd(c[0], c[1], c[2], 0.0));
                macro_rules! pick {
                    ($k:expr) => {{
                        let (idx, sign) = &lanes[$k];
                        // SAFETY: 8 i32 and 4 f64, unaligned loads.
                        let (i, s) = unsafe {
                            (
                                _mm256_loadu_si256(idx.as_ptr().cast()),
                                _mm256_loadu_pd(sign.as_ptr()),
                            )
                        };
                        let p = _mm256_castps_pd(_mm256_permutevar8x32_ps(src, i));
                        _mm256_mul_pd(s, p)
                    }};
                }
                let (x, y, z) = (pick!(0), pick!(1), pick!(2));
                let planes = [
                    _mm256_sub_pd(_mm256_xor_pd(z, neg), near),
                    _mm256_add_pd(x, _mm256_mul_pd(a_lo, z)),
                    _mm256_sub_pd(_mm256_xor_pd(x, neg), _mm256_mul_pd(a_hi, z)),
                    _mm256_add_pd(y, _mm256_mul_pd(b_lo, z)),
                    _mm256_sub_pd(_mm256_xor_pd(y, neg), _mm256_mul_pd(b_hi, z)),
                ];
                for (a, p) in all.iter_mut().zip(planes) {
                    *a = _mm256_and_pd(*a, _mm256_cmp_pd::<_CMP_NGE_UQ>(p, zero));
                }
            }
            let any = _mm256_or_pd(
                _mm256_or_pd(_mm256_or_pd(all[0], all[1]), _mm256_or_pd(all[2], all[3])),
                all[4],
            );
            culled |= (_mm256_movemask_pd(any) as u32) << (4 * v);
        }
        let n = self.faces.len();
        (!culled & ((1 << n) - 1)) << self.faces[0].view
    }
}

fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dirt::clip::Poly;
    use glam::{DVec3, Vec3};
    use parallax_scene::camera::{CubeMap, Pinhole};

    /// The cull keeps exactly the faces whose setup returns an entry or clips the triangle
    /// away (never one the setup's outcodes drop), the AVX and the scalar versions the same,
    /// on random triangles around the eye: small and large, near the face boundaries (the
    /// planes `x = ±y`...), through the near plane, with zero components.
    #[test]
    fn cull_equals_the_setup_outcodes() {
        let cube = CubeMap {
            eye: Vec3::new(0.5, -1.25, 3.0),
            face: 32,
        };
        let desc = parallax_scene::CameraDesc::new(
            Vec3::new(0.5, -1.25, 3.0),
            Vec3::new(-2.0, 0.5, 0.0),
            Vec3::Y,
            50.0,
        );
        let mut views: Vec<Pinhole> = vec![Pinhole::new(&desc, 64, 32).unwrap()];
        views.extend((0..6).map(|i| cube.face_camera(i)));
        let xfs: Vec<ViewXf> = views.iter().map(|v| ViewXf::new(v, 1e-3)).collect();
        let cull = FaceCull::new(&xfs).expect("the six faces");
        assert_eq!(cull.members(), 0b111_1110);
        assert_eq!(cull.first_view(), 1);
        let eye = cube.eye.as_dvec3();
        let mut rng = parallax_core::Rng::new(5, 7);
        let mut poly = Poly::EMPTY;
        let (mut kept, mut dropped, mut clipped_away) = (0u64, 0u64, 0u64);
        for i in 0..20_000 {
            let mut u = || rng.next_f32() as f64 - 0.5;
            let size = [1e-3, 0.1, 2.0, 50.0][i % 4];
            let centre = DVec3::new(u(), u(), u()) * [0.01, 1.0, 10.0][i % 3];
            let mut corner = |c: DVec3| {
                let mut p = c + DVec3::new(u(), u(), u()) * size;
                // Corners on the faces' boundary planes and on the axes.
                match i % 7 {
                    0 => p.y = p.x,
                    1 => p.z = -p.x,
                    2 => p.x = 0.0,
                    _ => {}
                }
                // Through f32, as the mesh holds them.
                (p + eye).as_vec3().as_dvec3()
            };
            let p = [corner(centre), corner(centre), corner(centre)];
            let d = p.map(|p| (p - eye).to_array());
            let keep = cull.keep(&d);
            assert_eq!(keep, cull.keep_portable(&d), "triangle {i}");
            for (k, xf) in xfs.iter().enumerate().skip(1) {
                let entry = xf.setup(0, &d, 1.0, &mut poly);
                let outcode_culled = xf.outcode_culled(&d);
                assert_eq!(keep >> k & 1 == 0, outcode_culled, "triangle {i} face {k}");
                if outcode_culled {
                    assert!(entry.is_none(), "triangle {i} face {k}");
                    dropped += 1;
                } else if entry.is_some() {
                    kept += 1;
                } else {
                    clipped_away += 1;
                }
            }
        }
        assert!(
            kept > 10_000 && dropped > 50_000,
            "{kept} {dropped} {clipped_away}"
        );
    }
}
