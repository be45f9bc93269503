//! Every saved fuzz finding in `crates/fuzz/regressions/` runs without a panic and under the
//! default peak-heap budget (a finding copied there from `out/fuzz/` becomes a test).

use parallax_fuzz::targets::Target;
use parallax_fuzz::{FuzzOptions, alloc};

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

#[test]
fn saved_findings_do_not_panic_or_blow_the_budget() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    let work = std::env::temp_dir().join(format!("parallax-fuzz-reg-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    let budget = FuzzOptions::default().budget_bytes;
    let mut n = 0;
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    files.sort();
    for p in files {
        let Some(t) = p
            .extension()
            .and_then(|x| x.to_str())
            .and_then(Target::of_ext)
        else {
            continue;
        };
        let data = std::fs::read(&p).unwrap();
        let base = alloc::reset_peak();
        t.run(&data, &work.join(format!("case.{}", t.ext())))
            .unwrap();
        let peak = alloc::peak() - base;
        assert!(peak <= budget, "{}: peak heap {peak} bytes", p.display());
        n += 1;
    }
    assert!(n >= 3, "the saved findings are there ({n})");
    let _ = std::fs::remove_dir_all(work);
}
