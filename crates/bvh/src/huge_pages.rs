//! Transparent huge pages for the build's large arrays (the references, the binary arena, the
//! collapses' nodes, triangles and blocks).
//!
//! Each of these arrays is written once, shortly after it is allocated, so in a fresh process
//! every 4 KiB page of it is first touched by the build: one minor page fault (and a zeroed
//! page) per 4 KiB. [`huge_vec`] reserves the capacity and asks the kernel
//! (`madvise(MADV_HUGEPAGE)`, Linux) to back the whole 2 MiB pages inside the untouched
//! allocation with transparent huge pages, one fault per 2 MiB, where the system's THP mode is
//! `always` or `madvise`. The advice changes neither the contents nor the layout: on other
//! systems, with THP off, or where the kernel refuses, the vector is an ordinary one.

/// The transparent huge page size of x86-64 and of 4 KiB-page arm64 kernels.
pub(crate) const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for `cap` elements, whose whole 2 MiB pages are advised to be
/// huge pages (module docs). Call it before anything is written to the memory: pages already
/// touched stay as they are.
pub(crate) fn huge_vec<T>(cap: usize) -> Vec<T> {
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
