//! The rasterization's output before the band fill (DIRT §4.1, between the fused setup /
//! rasterization and "Fill Depth"): one view's fragments of one chunk of the mesh, per screen
//! band, and the pool that keeps these buffers from one build to the next.
//!
//! A chunk's task fills one buffer per view and band and hands the buffers themselves to the
//! fill (no copy into a contiguous array); once every band is filled, the buffers go back to
//! the pool, emptied, and the next build's chunks take them from there (per view index, so
//! each buffer meets the same band shape again). A warm build therefore neither copies the
//! fragments nor asks the kernel for fresh pages for them. The pool keeps at most
//! [`MAX_POOL_BYTES`] of buffer capacity; what does not fit is freed.

use std::sync::Mutex;

use super::fill::RawFrag;

/// Buffer capacity the pool keeps at most, in bytes.
const MAX_POOL_BYTES: usize = 256 << 20;

/// One view's fragments of one chunk of triangles, per screen band (`bands[b]`, in triangle
/// order).
#[derive(Default)]
pub(super) struct ViewFrags {
    pub bands: Vec<Vec<RawFrag>>,
    /// Triangles whose clipped projection touches a cell row of the view.
    pub in_view: u64,
}

impl ViewFrags {
    /// Band `b`'s fragments.
    #[inline]
    pub fn band(&self, b: u32) -> &[RawFrag] {
        &self.bands[b as usize]
    }

    /// Fragments in all bands.
    pub fn len(&self) -> usize {
        self.bands.iter().map(Vec::len).sum()
    }
}

/// Emptied band buffers of earlier builds: per view index, a stack of per-band sets.
static POOL: Mutex<Vec<Vec<Vec<Vec<RawFrag>>>>> = Mutex::new(Vec::new());

fn pool() -> std::sync::MutexGuard<'static, Vec<Vec<Vec<Vec<RawFrag>>>>> {
    POOL.lock().unwrap_or_else(|e| e.into_inner())
}

/// For each view `v`, `bands[v]` empty band buffers (from the pool where it has a set).
pub(super) fn take_sets(bands: impl ExactSizeIterator<Item = usize>) -> Vec<Vec<Vec<RawFrag>>> {
    let mut sets: Vec<Vec<Vec<RawFrag>>> = {
        let mut p = pool();
        (0..bands.len())
            .map(|v| p.get_mut(v).and_then(Vec::pop).unwrap_or_default())
            .collect()
    };
    for (set, n) in sets.iter_mut().zip(bands) {
        set.resize_with(n, Vec::new);
        set.iter_mut().for_each(Vec::clear);
    }
    sets
}

/// Gives the buffers of `frags` (`frags[view][chunk]`) back to the pool, emptied, up to
/// [`MAX_POOL_BYTES`] of capacity in all.
pub(super) fn recycle(frags: Vec<Vec<ViewFrags>>) {
    let size = |set: &Vec<Vec<RawFrag>>| {
        set.iter().map(Vec::capacity).sum::<usize>() * std::mem::size_of::<RawFrag>()
    };
    let mut p = pool();
    let mut bytes: usize = p.iter().flatten().map(size).sum();
    if p.len() < frags.len() {
        p.resize_with(frags.len(), Vec::new);
    }
    for (stack, chunks) in p.iter_mut().zip(frags) {
        for mut f in chunks {
            let b = size(&f.bands);
            if bytes + b > MAX_POOL_BYTES {
                continue;
            }
            bytes += b;
            f.bands.iter_mut().for_each(Vec::clear);
            stack.push(f.bands);
        }
    }
}

/// Capacity (bytes) the pool holds now.
#[cfg(test)]
pub(super) fn pool_bytes() -> usize {
    pool()
        .iter()
        .flatten()
        .flatten()
        .map(|b| b.capacity() * std::mem::size_of::<RawFrag>())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Buffers come back empty and with their band count, whatever set the pool held.
    #[test]
    fn taken_sets_are_empty_and_shaped() {
        let frag = RawFrag::default();
        let full = ViewFrags {
            bands: vec![vec![frag; 5]; 9],
            in_view: 1,
        };
        recycle(vec![vec![full], Vec::new()]);
        assert!(pool_bytes() >= 45 * std::mem::size_of::<RawFrag>());
        for _ in 0..3 {
            let sets = take_sets([4usize, 2].into_iter());
            assert_eq!(sets.len(), 2);
            assert_eq!(sets[0].len(), 4);
            assert_eq!(sets[1].len(), 2);
            assert!(sets.iter().flatten().all(Vec::is_empty));
        }
    }
}
