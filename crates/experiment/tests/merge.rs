//! `results::merge`: disjoint and complete shards merge; gaps, overlaps and different jobs are
//! errors; file conflicts are caught.

use std::path::{Path, PathBuf};

use parallax_experiment::Shard;
use parallax_experiment::results::{MANIFEST_FILE, ShardManifest, merge, write_json};

fn shard_dir(root: &Path, index: usize, count: usize, total: usize, items: Vec<usize>) -> PathBuf {
    let d = root.join(format!("s{index}"));
    std::fs::create_dir_all(d.join("sub")).unwrap();
    for &i in &items {
        std::fs::write(d.join("sub").join(format!("f{i}.txt")), format!("item {i}")).unwrap();
    }
    let m = ShardManifest {
        kind: "files".into(),
        shard: Shard::new(index, count).unwrap(),
        total,
        items,
        results: None,
    };
    write_json(&d.join(MANIFEST_FILE), &m).unwrap();
    d
}

#[test]
fn merge_checks_completeness_and_overlap() {
    let root = std::env::temp_dir().join(format!("parallax-merge-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let a = shard_dir(&root, 0, 2, 5, vec![0, 2, 4]);
    let b = shard_dir(&root, 1, 2, 5, vec![1, 3]);
    let out = root.join("out");
    let s = merge(&[a.clone(), b.clone()], &out).unwrap();
    assert_eq!((s.items, s.files), (5, 5));
    assert!(!out.join(MANIFEST_FILE).exists());
    assert_eq!(
        std::fs::read_to_string(out.join("sub/f3.txt")).unwrap(),
        "item 3"
    );
    let m = merge(std::slice::from_ref(&a), &root.join("out2"))
        .unwrap_err()
        .to_string();
    assert!(m.contains("2 of 5 items missing"), "{m}");
    let c = shard_dir(&root.join("c"), 1, 2, 5, vec![1, 2, 3]);
    let m = merge(&[a.clone(), c], &root.join("out3"))
        .unwrap_err()
        .to_string();
    assert!(m.contains("item 2 is in both"), "{m}");
    let d = shard_dir(&root.join("d"), 1, 3, 5, vec![1, 3]);
    assert!(merge(&[a, d], &root.join("out4")).is_err());
    let _ = std::fs::remove_dir_all(&root);
}
