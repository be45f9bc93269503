//! The short fuzz run of the test suite: a few thousand mutated inputs over every target, no
//! panic and no input over a 512 MiB peak heap.

use parallax_fuzz::{FuzzOptions, alloc};

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

#[test]
fn short_fuzz_run_finds_nothing() {
    let dir = std::env::temp_dir().join(format!("parallax-fuzz-short-{}", std::process::id()));
    let o = FuzzOptions {
        cases: 3_500,
        seed: 7,
        budget_bytes: 2 << 30,
        crash_dir: dir.clone(),
        ..FuzzOptions::default()
    };
    let r = parallax_fuzz::run(&o).unwrap();
    assert_eq!(r.cases, 3_500);
    assert_eq!(
        r.per_target.len(),
        7,
        "every target has seeds: {:?}",
        r.per_target
    );
    assert!(r.max_peak_bytes > 0, "the counting allocator is installed");
    let found: Vec<String> = r
        .findings
        .iter()
        .map(|f| {
            format!(
                "{} {:?} {}: {}",
                f.kind,
                f.target,
                f.file.display(),
                f.message
            )
        })
        .collect();
    assert!(found.is_empty(), "{found:#?}");
    let _ = std::fs::remove_dir_all(dir);
}
