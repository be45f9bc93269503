//! The triangle buffer as the tracer's tests read it (Vardis et al. 2017, §3 (iii) "vertex
//! buffer" and Algorithm 1 line 13, `hit(r, pr_k)`): each distinct corner once, in a vertex
//! buffer, and per triangle the indices of its three corners, as the GPU version reads an
//! indexed vertex buffer.
//!
//! The capture's triangle buffer ([`DirtTri`], nine `f32` a triangle) repeats a corner for
//! every triangle that shares it (about six in a closed mesh). The tests of a ray read the
//! corners of triangles scattered over the whole buffer; a buffer of one vertex per distinct
//! corner plus three `u32` indices a triangle is smaller, so more of it stays in cache.
//!
//! **Exactness.** Corners are shared only when their three coordinates are equal bit for bit
//! (`-0.0` and `0.0` are different corners, a NaN is a corner of its own bits), so corner `k`
//! of triangle `i` read through the indices is bit for bit the capture's: the same test on the
//! same `f32` values gives the same answer (`tri4`, tested here and in `tests/dirt.rs`).
//!
//! **Order.** Vertices are numbered in the order the triangles (mesh order) first use them,
//! so triangles near each other in the mesh read vertices near each other.
//!
//! **Layout.** The vertex buffer ends with one padding vertex, so that a 16-byte load at any
//! corner (its three coordinates and the next `f32`, `tri4`'s gather) stays inside it.

use glam::Vec3;
use parallax_raster::dirt::DirtTri;

/// The shared-corner form of a triangle buffer (module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct Corners {
    /// Distinct corners in first-use order, then one padding vertex.
    verts: Vec<Vec3>,
    /// Per triangle, its corners' indices into `verts` (each `< verts.len() - 1`).
    idx: Vec<[u32; 3]>,
}

impl Corners {
    /// Shares the bit-equal corners of `tris` (one pass, an open-addressing table of vertex
    /// numbers keyed by the corner's bits).
    pub fn new(tris: &[DirtTri]) -> Corners {
        let n = tris.len() * 3;
        let size = (2 * n).next_power_of_two().max(16);
        let mask = size - 1;
        let mut table = vec![u32::MAX; size];
        let mut verts: Vec<Vec3> = Vec::with_capacity(n / 2 + 1);
        let mut vbits: Vec<[u32; 3]> = Vec::with_capacity(n / 2 + 1);
        let mut idx = Vec::with_capacity(tris.len());
        for t in tris {
            let mut ix = [0u32; 3];
            for (k, p) in [t.p0, t.p1, t.p2].into_iter().enumerate() {
                let b = p.to_array().map(f32::to_bits);
                let h = (b[0] as u64)
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .rotate_left(21)
                    ^ (b[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
                    ^ (b[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
                let mut s = (h >> 32) as usize & mask;
                ix[k] = loop {
                    let v = table[s];
                    if v == u32::MAX {
                        let v = verts.len() as u32;
                        table[s] = v;
                        verts.push(p);
                        vbits.push(b);
                        break v;
                    }
                    if vbits[v as usize] == b {
                        break v;
                    }
                    s = (s + 1) & mask;
                };
            }
            idx.push(ix);
        }
        verts.push(Vec3::ZERO);
        Corners { verts, idx }
    }

    /// Number of triangles.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.idx.len()
    }

    /// Number of distinct corners (without the padding vertex).
    pub fn vertex_count(&self) -> usize {
        self.verts.len() - 1
    }

    /// Triangle `id`'s corner indices.
    #[inline(always)]
    pub fn indices(&self, id: u32) -> [u32; 3] {
        self.idx[id as usize]
    }

    /// Triangle `id`'s corners, bit for bit the capture's.
    #[inline(always)]
    pub fn tri(&self, id: u32) -> [Vec3; 3] {
        self.idx[id as usize].map(|i| self.verts[i as usize])
    }

    /// The vertex buffer, padding vertex included: every index of [`Self::indices`] `i`
    /// has floats `3 i .. 3 i + 4` inside it.
    #[inline(always)]
    pub fn verts(&self) -> &[Vec3] {
        &self.verts
    }

    /// Bytes of the vertex buffer and the indices.
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of_val(self.verts.as_slice()) + std::mem::size_of_val(self.idx.as_slice()))
            as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::sampling::Rng;

    /// Every triangle's corners read back bit for bit, on shared, special (zeros of both
    /// signs, infinities, NaNs, subnormals) and random corners; bit-equal corners are shared,
    /// others are not.
    #[test]
    fn corners_read_back_bit_for_bit() {
        let mut rng = Rng::for_pixel(3, 1, 4, 1);
        let special = [
            0.0f32,
            -0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            1e-42,
            -1e-42,
        ];
        let mut pool: Vec<Vec3> = (0..40)
            .map(|i| {
                let mut c = [0.0f32; 3];
                for (k, x) in c.iter_mut().enumerate() {
                    *x = if (i + k) % 5 == 0 {
                        special[(i * 3 + k) % special.len()]
                    } else {
                        (rng.next_f32() - 0.5) * 10.0
                    };
                }
                Vec3::from(c)
            })
            .collect();
        // Two points differing only in the sign of a zero.
        pool.push(Vec3::new(1.0, 0.0, 2.0));
        pool.push(Vec3::new(1.0, -0.0, 2.0));
        let tris: Vec<DirtTri> = (0..500)
            .map(|_| {
                let mut pick = || pool[(rng.next_f32() * pool.len() as f32) as usize % pool.len()];
                DirtTri {
                    p0: pick(),
                    p1: pick(),
                    p2: pick(),
                }
            })
            .collect();
        let c = Corners::new(&tris);
        assert_eq!(c.len(), tris.len());
        let bits = |p: Vec3| p.to_array().map(f32::to_bits);
        for (i, t) in tris.iter().enumerate() {
            let got = c.tri(i as u32).map(bits);
            assert_eq!(got, [t.p0, t.p1, t.p2].map(bits));
            for v in c.indices(i as u32) {
                assert!((v as usize) < c.vertex_count());
            }
        }
        // Shared exactly by bits: as many vertices as distinct bit patterns used.
        let mut distinct: Vec<[u32; 3]> = tris
            .iter()
            .flat_map(|t| [t.p0, t.p1, t.p2].map(bits))
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(c.vertex_count(), distinct.len());
        assert!(c.vertex_count() < tris.len() * 3 / 4, "{}", c.vertex_count());
        assert_eq!(c.verts().len(), c.vertex_count() + 1);
    }

    #[test]
    fn empty_buffer() {
        let c = Corners::new(&[]);
        assert_eq!(c.vertex_count(), 0);
        assert_eq!(c.verts().len(), 1);
    }
}
