//! Transparent huge pages for large arrays written once after they are allocated: the BVH
//! build's references, binary arena and collapse outputs, and the beam caster's visibility
//! buffer.
//!
//! In a fresh process every 4 KiB page of such an array is first touched when it is written:
//! one minor page fault (and a zeroed page) per 4 KiB. [`huge_vec`] reserves the capacity and
//! asks the kernel (`madvise(MADV_HUGEPAGE)`, Linux) to back the whole 2 MiB pages inside the
//! untouched allocation with transparent huge pages, one fault per 2 MiB, where the system's
//! THP mode is `always` or `madvise`. The advice changes neither the contents nor the layout:
//! on other systems, with THP off, or where the kernel refuses, the vector is an ordinary
//! one. A vector's first and last partial 2 MiB stay 4 KiB pages; [`HugeBuf`] is whole 2 MiB
//! pages instead, and starts on a cache line whatever its size: the arrays written by
//! whole-line non-temporal stores (a misaligned 64-byte run fills two half lines, each
//! written back as a partial line; measurements in `docs/notes/vr.md`).

use std::alloc::{Layout, alloc, dealloc, handle_alloc_error};
use std::ops::{Deref, DerefMut};
use std::ptr::NonNull;

/// The cache line of x86-64 and of most arm64 cores: [`HugeBuf`]'s smallest alignment.
pub const CACHE_LINE: usize = 64;

/// The transparent huge page size of x86-64 and of 4 KiB-page arm64 kernels.
pub const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for `cap` elements, whose whole 2 MiB pages are advised to be
/// huge pages (module docs). Call it before anything is written to the memory: pages already
/// touched stay as they are.
pub fn huge_vec<T>(cap: usize) -> Vec<T> {
    let v: Vec<T> = Vec::with_capacity(cap);
    advise_huge(v.as_ptr().cast(), cap.saturating_mul(size_of::<T>()));
    v
}

/// The whole [`HUGE_PAGE`]s inside `len` bytes from `p`, as `(start, length)`; `None` if none.
fn huge_range(p: usize, len: usize) -> Option<(usize, usize)> {
    let start = p.checked_next_multiple_of(HUGE_PAGE)?;
    let end = p.checked_add(len)? / HUGE_PAGE * HUGE_PAGE;
    (end > start).then(|| (start, end - start))
}

/// `len` copies of a value in an allocation of whole [`HUGE_PAGE`]s, aligned to one, when it
/// spans at least one, advised as [`huge_vec`]: every 2 MiB of it can be a huge page, where a
/// vector's first and last partial 2 MiB stay 4 KiB pages. Smaller ones start on a
/// [`CACHE_LINE`]. A fixed-length slice otherwise (`Deref`).
pub struct HugeBuf<T: Copy> {
    ptr: NonNull<T>,
    len: usize,
    layout: Layout,
}

// SAFETY: `HugeBuf` owns its elements as a `Vec` does.
unsafe impl<T: Copy + Send> Send for HugeBuf<T> {}
// SAFETY: shared access only reads the elements.
unsafe impl<T: Copy + Sync> Sync for HugeBuf<T> {}

impl<T: Copy> HugeBuf<T> {
    pub fn new(len: usize, value: T) -> Self {
        let size = size_of::<T>()
            .checked_mul(len)
            .expect("HugeBuf size overflows");
        // At least one huge page: whole huge pages, the last one included.
        let (size, align) = if size >= HUGE_PAGE {
            let whole = size.checked_next_multiple_of(HUGE_PAGE);
            (whole.expect("HugeBuf size overflows"), HUGE_PAGE)
        } else {
            (size, align_of::<T>().max(CACHE_LINE))
        };
        let layout = Layout::from_size_align(size, align).expect("HugeBuf layout");
        let ptr = if size == 0 {
            NonNull::dangling()
        } else {
            // SAFETY: the layout's size is not zero.
            let p = unsafe { alloc(layout) }.cast::<T>();
            NonNull::new(p).unwrap_or_else(|| handle_alloc_error(layout))
        };
        advise_huge(ptr.as_ptr().cast(), size);
        for i in 0..len {
            // SAFETY: `i < len`, inside the allocation of `len` elements (or `T` is zero-sized).
            unsafe { ptr.as_ptr().add(i).write(value) };
        }
        HugeBuf { ptr, len, layout }
    }
}

impl<T: Copy> HugeBuf<T> {
    /// A copy of `v` in a new buffer of its length.
    pub fn from_slice(v: &[T]) -> Self
    where
        T: Default,
    {
        let mut b = Self::new(v.len(), T::default());
        b.copy_from_slice(v);
        b
    }
}

impl<T: Copy + Default> Clone for HugeBuf<T> {
    fn clone(&self) -> Self {
        Self::from_slice(self)
    }
}

impl<T: Copy + std::fmt::Debug> std::fmt::Debug for HugeBuf<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<T: Copy + PartialEq> PartialEq for HugeBuf<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<'a, T: Copy> IntoIterator for &'a HugeBuf<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl<'a, T: Copy> IntoIterator for &'a mut HugeBuf<T> {
    type Item = &'a mut T;
    type IntoIter = std::slice::IterMut<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter_mut()
    }
}

impl<T: Copy> Deref for HugeBuf<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        // SAFETY: `len` initialised elements from `ptr`, owned by `self`.
        unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
    }
}

impl<T: Copy> DerefMut for HugeBuf<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as `deref`, borrowed mutably through `self`.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len) }
    }
}

impl<T: Copy> Drop for HugeBuf<T> {
    fn drop(&mut self) {
        if self.layout.size() != 0 {
            // SAFETY: allocated in `new` with this layout (`T: Copy` needs no drop).
            unsafe { dealloc(self.ptr.as_ptr().cast(), self.layout) };
        }
    }
}

#[cfg(target_os = "linux")]
fn advise_huge(p: *const u8, len: usize) {
    if let Some((start, len)) = huge_range(p as usize, len) {
        // SAFETY: the range lies inside one live allocation (the vector's capacity), and
        // `MADV_HUGEPAGE` only changes how the kernel backs it, not its contents. An error
        // (THP not built into the kernel) leaves the memory as it was, so it is ignored.
        unsafe {
            libc::madvise(start as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge(_: *const u8, _: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_range_is_the_whole_huge_pages_inside() {
        const H: usize = HUGE_PAGE;
        assert_eq!(huge_range(0, H), Some((0, H)));
        assert_eq!(huge_range(1, H), None);
        assert_eq!(huge_range(4096, 3 * H), Some((H, 2 * H)));
        assert_eq!(huge_range(H - 16, 2 * H + 16), Some((H, 2 * H)));
        assert_eq!(huge_range(H + 1, 2 * H), Some((2 * H, H)));
        assert_eq!(huge_range(H + 1, H), None);
        assert_eq!(huge_range(usize::MAX - 10, 5), None);
    }

    #[test]
    fn huge_vec_has_the_capacity_and_keeps_what_is_written() {
        let n = 3 * HUGE_PAGE / 4 + 123;
        let mut v: Vec<u32> = huge_vec(n);
        assert!(v.is_empty() && v.capacity() >= n);
        v.extend((0..n as u32).map(|i| i.wrapping_mul(2654435761)));
        assert!(
            v.iter()
                .enumerate()
                .all(|(i, &x)| x == (i as u32).wrapping_mul(2654435761))
        );
        let e: Vec<[u8; 0]> = huge_vec(1 << 40);
        assert!(e.is_empty());
    }

    #[test]
    fn huge_buf_holds_the_value_and_its_big_allocations_start_at_a_huge_page() {
        for len in [0usize, 1, 1000, HUGE_PAGE / 36 + 1, 3 * HUGE_PAGE / 36 + 7] {
            let mut b = HugeBuf::new(len, [7u32; 9]);
            assert_eq!(b.len(), len);
            assert!(b.iter().all(|x| *x == [7; 9]));
            assert!(
                len == 0 || (b.as_ptr() as usize).is_multiple_of(CACHE_LINE),
                "{len}"
            );
            if len * 36 >= HUGE_PAGE {
                assert_eq!(b.as_ptr() as usize % HUGE_PAGE, 0);
                assert_eq!(b.layout.size() % HUGE_PAGE, 0);
                assert!(b.layout.size() >= len * 36);
            }
            if let Some(x) = b.last_mut() {
                x[0] = 1;
                assert_eq!(b[len - 1][0], 1);
            }
        }
        assert_eq!(HugeBuf::new(5, ()).len(), 5);
    }

    /// Where the kernel has transparent huge pages, the advised range is marked (`hg` in the
    /// mapping's `VmFlags` in `/proc/self/smaps`).
    #[cfg(target_os = "linux")]
    #[test]
    fn huge_vec_marks_its_huge_pages() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage/enabled").exists() {
            return; // no THP in this kernel: madvise refuses, nothing to check
        }
        let v: Vec<u64> = huge_vec(3 * HUGE_PAGE / 8);
        let (start, _) = huge_range(v.as_ptr() as usize, 3 * HUGE_PAGE).expect("a whole page");
        let smaps = std::fs::read_to_string("/proc/self/smaps").expect("smaps");
        let mut inside = false;
        let mut flags = None;
        for line in smaps.lines() {
            let range = line
                .split_whitespace()
                .next()
                .and_then(|r| r.split_once('-'));
            if let Some((a, b)) = range
                && let (Ok(a), Ok(b)) = (usize::from_str_radix(a, 16), usize::from_str_radix(b, 16))
            {
                inside = a <= start && start < b;
            } else if inside && let Some(f) = line.strip_prefix("VmFlags:") {
                flags = Some(f.to_string());
            }
        }
        let flags = flags.expect("the vector's mapping in smaps");
        assert!(
            flags.split_whitespace().any(|f| f == "hg"),
            "VmFlags:{flags}"
        );
        drop(v);
    }
}
