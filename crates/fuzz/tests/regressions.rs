//! Every saved fuzz finding in `crates/fuzz/regressions/` runs without a panic (a finding
//! copied there from `out/fuzz/` becomes a test).

use parallax_fuzz::targets::Target;

#[test]
fn saved_findings_do_not_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    let work = std::env::temp_dir().join(format!("parallax-fuzz-reg-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let p = e.path();
        let Some(t) = p
            .extension()
            .and_then(|x| x.to_str())
            .and_then(Target::of_ext)
        else {
            continue;
        };
        let data = std::fs::read(&p).unwrap();
        t.run(&data, &work.join(format!("case.{}", t.ext())));
        n += 1;
    }
    println!("{n} saved finding(s) ran");
    let _ = std::fs::remove_dir_all(work);
}
