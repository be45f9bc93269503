//! Seeded mutations of valid inputs (the AFL / libFuzzer havoc stage, hand-written because
//! cargo-fuzz needs a nightly toolchain): byte flips, random and "interesting" bytes and
//! integers, inserts, deletes, duplicated ranges and splices with another seed; glTF JSON
//! field mutations (any value replaced by a boundary value of another type, or removed, also
//! inside a GLB's JSON chunk with its lengths kept consistent); TOML line mutations (a
//! value replaced by a boundary value, lines duplicated or dropped).
//!
//! Invariants: a mutation depends only on the generator's state (runs are reproducible from
//! the seed); outputs stay below [`MAX_LEN`] bytes.

/// Largest mutated input.
pub const MAX_LEN: usize = 1 << 20;

/// A small, fast, seedable generator (SplitMix64).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9e37_79b9_7f4a_7c15)
    }
    /// The next 64 random bits (one SplitMix64 step).
    #[allow(clippy::should_implement_trait)] // a public generator step, not an iterator
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n >= 1`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    pub fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }
}

const INTERESTING_U32: [u32; 10] = [
    0,
    1,
    0x7f,
    0x80,
    0xff,
    0xffff,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_fffe,
    0xffff_ffff,
];

/// One to four stacked byte mutations of `data` (`other`: a second seed to splice from).
pub fn havoc(data: &[u8], other: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut d = data.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = d.len();
        match rng.below(8) {
            0 if n > 0 => {
                let i = rng.below(n);
                d[i] ^= 1 << rng.below(8);
            }
            1 if n > 0 => {
                let i = rng.below(n);
                d[i] = rng.next() as u8;
            }
            2 if n >= 4 => {
                let i = rng.below(n - 3);
                let v = INTERESTING_U32[rng.below(INTERESTING_U32.len())];
                let bytes = if rng.chance(2) {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                };
                d[i..i + 4].copy_from_slice(&bytes);
            }
            3 => {
                let i = rng.below(n + 1);
                let k = 1 + rng.below(16);
                let ins: Vec<u8> = (0..k).map(|_| rng.next() as u8).collect();
                d.splice(i..i, ins);
            }
            4 if n > 0 => {
                let i = rng.below(n);
                let k = 1 + rng.below((n - i).min(64));
                d.drain(i..i + k);
            }
            5 if n > 0 => {
                let i = rng.below(n);
                let k = 1 + rng.below((n - i).min(64));
                let copy = d[i..i + k].to_vec();
                let at = rng.below(n + 1);
                d.splice(at..at, copy);
            }
            6 if !other.is_empty() && n > 0 => {
                let cut = rng.below(n);
                let from = rng.below(other.len());
                d.truncate(cut);
                d.extend_from_slice(&other[from..]);
            }
            _ if n > 0 => {
                // An ASCII digit run: numbers in text formats.
                let i = rng.below(n);
                let digits = [
                    "0",
                    "-1",
                    "4294967295",
                    "1e309",
                    "nan",
                    "99999999999999999999",
                    "-0",
                ];
                let s = digits[rng.below(digits.len())].as_bytes();
                let end = (i + s.len()).min(n);
                d.splice(i..end, s.iter().copied());
            }
            _ => d.push(rng.next() as u8),
        }
    }
    d.truncate(MAX_LEN);
    d
}

fn boundary_json(rng: &mut Rng) -> serde_json::Value {
    use serde_json::json;
    match rng.below(14) {
        0 => json!(-1),
        1 => json!(0),
        2 => json!(4294967295u64),
        3 => json!(9007199254740993u64),
        4 => json!(1e308),
        5 => json!(-1e308),
        6 => json!(""),
        7 => json!("data:application/octet-stream;base64,AAAA"),
        8 => json!([]),
        9 => json!({}),
        10 => serde_json::Value::Null,
        11 => json!(true),
        12 => json!([0, 0, 0]),
        _ => json!(0.5),
    }
}

/// Every (parent path, key or index) of a JSON tree, depth-first.
fn slots(v: &serde_json::Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                path.push(k.clone());
                out.push(path.clone());
                slots(x, path, out);
                path.pop();
            }
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                path.push(i.to_string());
                out.push(path.clone());
                slots(x, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

/// Replaces (or removes) one to three fields of a JSON document by boundary values.
pub fn mutate_json(text: &[u8], rng: &mut Rng) -> Option<Vec<u8>> {
    let mut v: serde_json::Value = serde_json::from_slice(text).ok()?;
    for _ in 0..1 + rng.below(3) {
        let mut all = Vec::new();
        slots(&v, &mut Vec::new(), &mut all);
        if all.is_empty() {
            break;
        }
        let path = all[rng.below(all.len())].clone();
        let (last, parent) = path.split_last()?;
        let mut node = &mut v;
        for p in parent {
            node = match node {
                serde_json::Value::Object(m) => m.get_mut(p)?,
                serde_json::Value::Array(a) => a.get_mut(p.parse::<usize>().ok()?)?,
                _ => return None,
            };
        }
        let remove = rng.chance(5);
        let value = boundary_json(rng);
        match node {
            serde_json::Value::Object(m) => {
                if remove {
                    m.remove(last);
                } else {
                    m.insert(last.clone(), value);
                }
            }
            serde_json::Value::Array(a) => {
                let i: usize = last.parse().ok()?;
                if remove {
                    a.remove(i);
                } else {
                    a[i] = value;
                }
            }
            _ => {}
        }
    }
    serde_json::to_vec(&v).ok()
}

/// The JSON and BIN chunks of a GLB (`None` if it is not one).
pub fn glb_chunks(glb: &[u8]) -> Option<(Vec<u8>, Vec<u8>)> {
    let u32_at = |i: usize| Some(u32::from_le_bytes(glb.get(i..i + 4)?.try_into().ok()?) as usize);
    if glb.get(0..4)? != b"glTF" {
        return None;
    }
    let json_len = u32_at(12)?;
    let json = glb.get(20..20 + json_len)?.to_vec();
    let bin = match u32_at(20 + json_len) {
        Some(bin_len) => glb.get(28 + json_len..28 + json_len + bin_len)?.to_vec(),
        None => Vec::new(),
    };
    Some((json, bin))
}

/// A GLB of a JSON and a BIN chunk, lengths and padding as the spec says.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b);
    }
    out
}

/// Replaces one line's value (after `=`) by a boundary TOML value, or duplicates / drops a line.
pub fn mutate_toml(text: &[u8], rng: &mut Rng) -> Vec<u8> {
    let s = String::from_utf8_lossy(text);
    let mut lines: Vec<String> = s.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return text.to_vec();
    }
    let values = [
        "-1",
        "0",
        "9223372036854775807",
        "-9223372036854775808",
        "1e308",
        "inf",
        "nan",
        "\"\"",
        "[]",
        "[[]]",
        "{}",
        "true",
        "\"../../nope.glb\"",
        "[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15]",
        "\"quadtree,dda\"",
        "1979-05-27",
        "[1, \"a\", 2.5]",
        "{ a = { b = 1 } }",
    ];
    let i = rng.below(lines.len());
    match rng.below(4) {
        0 => {
            let l = lines[i].clone();
            lines.insert(i, l);
        }
        1 => {
            lines.remove(i);
        }
        _ => {
            if let Some((k, _)) = lines[i].split_once('=') {
                lines[i] = format!("{k}= {}", values[rng.below(values.len())]);
            } else {
                let k = [
                    "bench",
                    "title",
                    "width",
                    "max_points",
                    "scene",
                    "sweep.x",
                    "[sweep]",
                    "[args]",
                    "[images]",
                ];
                lines.insert(
                    i,
                    format!(
                        "{} = {}",
                        k[rng.below(k.len())],
                        values[rng.below(values.len())]
                    ),
                );
            }
        }
    }
    let mut out = lines.join("\n").into_bytes();
    out.push(b'\n');
    out
}
