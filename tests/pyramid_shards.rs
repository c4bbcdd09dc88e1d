//! `ridgeline import --shard K/N` and `--merge-shards N` as a user runs
//! them, each shard a separate process: four shards merged give the very
//! `pyramid.rlp` and `meshes.rlm` one process writes, over two layers (a
//! coarse grid under a mosaic of two finer tiles with a small and a large
//! void); a shard killed mid-run, or whose part was left damaged, reruns
//! to the same bytes; bad counts and missing, mismatched or damaged parts
//! are refused naming the file, and a failed merge leaves the previous
//! dataset as it was.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use ridgeline::meshes::MAP_FILE_NAME;
use ridgeline::pyramid::FILE_NAME;
use testkit::cli::{Ridgeline, Run};
use testkit::dem::write_ascii;
use testkit::fresh_dir;

/// Small nodes: shards split no finer than the share level (5), whose
/// nodes of 8 cells span 11.5 km at the fine tiles' 45 m posts, enough of
/// them under the fine tiles for four shards.
const NODE: &[&str] = &["--node-size", "8"];

fn terrain(x: f64, y: f64) -> f64 {
    900.0 + 400.0 * (x / 6100.0).sin() * (y / 8300.0).cos() + 0.004 * x + 30.0 * (x / 700.0).cos()
}

/// Writes an ESRI ASCII grid of `posts` at `spacing` metres from
/// `origin` (local metres), heights from `height` (NaN: no data).
fn write_grid(
    path: &Path,
    origin: [f64; 2],
    spacing: f64,
    posts: [usize; 2],
    height: impl Fn(f64, f64) -> f64,
) {
    let header = format!(
        "ncols {}\nnrows {}\nxllcenter {}\nyllcenter {}\ncellsize {spacing}\nnodata_value -9999\n",
        posts[0], posts[1], origin[0], origin[1]
    );
    let rows: Vec<Vec<String>> = (0..posts[1])
        .rev()
        .map(|j| {
            (0..posts[0])
                .map(|i| {
                    let (x, y) = (origin[0] + i as f64 * spacing, origin[1] + j as f64 * spacing);
                    let h = height(x, y);
                    if h.is_nan() {
                        "-9999".into()
                    } else {
                        format!("{h:.2}")
                    }
                })
                .collect()
        })
        .collect();
    write_ascii(path, &header, &rows);
}

/// A coarse grid (720 m) under two adjacent fine tiles (45 m), one with
/// a small void (filled) and one with a large void (the coarse grid shows
/// through); `bump` raises one fine post (another source).
fn write_sources(dir: &Path, bump: f64) -> Vec<PathBuf> {
    let coarse = dir.join("coarse.asc");
    write_grid(&coarse, [0.0, 0.0], 720.0, [100, 100], terrain);
    let west = dir.join("west.asc");
    write_grid(&west, [18_000.0, 21_600.0], 45.0, [401, 601], |x, y| {
        let small = (31_500.0..31_700.0).contains(&x) && (30_000.0..30_150.0).contains(&y);
        let bumped = x == 20_700.0 && y == 25_200.0;
        if small {
            f64::NAN
        } else {
            terrain(x, y) + 12.0 + if bumped { bump } else { 0.0 }
        }
    });
    let east = dir.join("east.asc");
    write_grid(&east, [36_000.0, 21_600.0], 45.0, [401, 601], |x, y| {
        let large = (40_000.0..43_000.0).contains(&x) && (30_000.0..34_000.0).contains(&y);
        if large {
            f64::NAN
        } else {
            terrain(x, y) + 12.0
        }
    });
    vec![coarse, west, east]
}

/// `ridgeline import` of `sources` into `out` with `args`.
fn import(args: &[&str], sources: &[PathBuf], out: &Path) -> Run {
    let ridgeline = Ridgeline::new(env!("CARGO_BIN_EXE_ridgeline"));
    ridgeline.args(["import"]).args(NODE).args(args).args(sources).arg("--out").arg(out)
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn part(dir: &Path, k: u32, n: u32, ext: &str) -> PathBuf {
    dir.join(format!("shard-{k}-of-{n}.{ext}"))
}

/// Runs the four shards as separate processes at once, then the merge.
fn shard_and_merge(sources: &[PathBuf], out: &Path) {
    let children: Vec<_> = (0..4)
        .map(|k| {
            let shard = format!("{k}/4");
            import(&["--shard", &shard], sources, out).spawn(Stdio::null(), Stdio::piped())
        })
        .collect();
    for child in children {
        child.finish().ok();
    }
    import(&["--merge-shards", "4"], sources, out).ok();
}

/// The dataset one process writes.
fn one_process(sources: &[PathBuf], dir: &Path) -> (Vec<u8>, Vec<u8>) {
    let out = dir.join("one");
    import(&[], sources, &out).ok();
    (read(&out.join(FILE_NAME)), read(&out.join(MAP_FILE_NAME)))
}

fn assert_same(out: &Path, expected: &(Vec<u8>, Vec<u8>), what: &str) {
    assert!(read(&out.join(FILE_NAME)) == expected.0, "{what}: pyramid.rlp differs");
    assert!(read(&out.join(MAP_FILE_NAME)) == expected.1, "{what}: meshes.rlm differs");
}

/// Names in `dir` a finished shard or merge leaves behind it by mistake.
fn leftovers(dir: &Path) -> Vec<String> {
    let names = std::fs::read_dir(dir).expect("list").flatten();
    let names = names.map(|e| e.file_name().to_string_lossy().into_owned());
    names.filter(|n| n.starts_with('.') || n.contains(".tmp-")).collect()
}

#[test]
fn four_shards_merge_into_the_bytes_of_one_process() {
    let dir = fresh_dir("shards-merge");
    let sources = write_sources(&dir, 0.0);
    let expected = one_process(&sources, &dir);
    let out = dir.join("four");
    shard_and_merge(&sources, &out);
    assert_same(&out, &expected, "four shards");
    assert!(leftovers(&out).is_empty(), "{:?}", leftovers(&out));
    // Every shard did part of the work: each part holds nodes.
    for k in 0..4 {
        let shard = import(&["--shard", &format!("{k}/4")], &sources, &out).ok();
        let said = shard.stdout();
        assert!(!said.contains("(0 nodes"), "shard {k}: {said}");
    }
    // One shard is the plain import split at its coarsest levels.
    let one = dir.join("one-shard");
    import(&["--shard", "0/1"], &sources, &one).ok();
    import(&["--merge-shards", "1"], &sources, &one).ok();
    assert_same(&one, &expected, "one shard");
}

#[test]
fn a_killed_or_damaged_shard_reruns_to_the_same_bytes() {
    let dir = fresh_dir("shards-kill");
    let sources = write_sources(&dir, 0.0);
    let out = dir.join("four");
    shard_and_merge(&sources, &out);
    let merged = (read(&out.join(FILE_NAME)), read(&out.join(MAP_FILE_NAME)));
    let parts: Vec<Vec<u8>> =
        ["rlp", "rlm"].iter().map(|ext| read(&part(&out, 2, 4, ext))).collect();

    // Killed while it writes: its previous parts stay whole (they are
    // renamed into place), and what it left (a temporary, its scratch) a
    // rerun clears.
    let mut child =
        import(&["--shard", "2/4"], &sources, &out).spawn(Stdio::null(), Stdio::null()).child;
    let started = Instant::now();
    let temporary = |dir: &Path| {
        let names = std::fs::read_dir(dir).expect("list").flatten();
        names.map(|e| e.file_name().to_string_lossy().into_owned()).any(|n| n.contains(".tmp-"))
    };
    while !temporary(&out) && started.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("kill the shard");
    child.wait().expect("reap");
    assert_eq!(read(&part(&out, 2, 4, "rlp")), parts[0], "the part is the old one or the new");
    import(&["--shard", "2/4"], &sources, &out).ok();
    assert_eq!(read(&part(&out, 2, 4, "rlp")), parts[0], "the rerun writes the same bytes");
    assert_eq!(read(&part(&out, 2, 4, "rlm")), parts[1], "the rerun writes the same bytes");
    assert!(leftovers(&out).is_empty(), "{:?}", leftovers(&out));

    // A part cut short (a copy interrupted, a full disk) is refused by
    // name; the rerun replaces it and the merge gives the same bytes.
    let rlm = part(&out, 2, 4, "rlm");
    std::fs::write(&rlm, &parts[1][..parts[1].len() / 3]).expect("truncate");
    let stale = dir.join("four").join("shard-2-of-4.rlp.tmp-4000000");
    std::fs::write(&stale, b"half a part of a dead process").expect("stale temporary");
    import(&["--merge-shards", "4"], &sources, &out)
        .refused(&[&rlm.display().to_string(), "--shard 2/4"]);
    import(&["--shard", "2/4"], &sources, &out).ok();
    assert!(!stale.exists(), "a dead shard's temporary is removed");
    import(&["--merge-shards", "4"], &sources, &out).ok();
    assert_same(&out, &merged, "after the reruns");
}

#[test]
fn bad_counts_and_parts_are_refused_naming_the_file() {
    let dir = fresh_dir("shards-bad");
    let sources = write_sources(&dir, 0.0);
    let out = dir.join("four");
    import(&["--shard", "4/4"], &sources, &out).refused(&["4/4", "K must be below N"]);
    import(&["--shard", "0/0"], &sources, &out).refused(&["0/0", "N must be at least 1"]);
    import(&["--shard", "two"], &sources, &out).refused(&["is not K/N"]);
    import(&["--merge-shards", "0"], &sources, &out).refused(&["N must be at least 1"]);
    let first = part(&out, 0, 4, "rlp").display().to_string();
    import(&["--merge-shards", "4"], &sources, &out).refused(&[&first, "missing", "--shard 0/4"]);
    assert!(!out.exists(), "a refused first merge leaves no directory");

    shard_and_merge(&sources, &out);
    let dataset = (read(&out.join(FILE_NAME)), read(&out.join(MAP_FILE_NAME)));
    let untouched = |what: &str| {
        assert_same(&out, &dataset, what);
        assert!(leftovers(&out).is_empty(), "{what}: {:?}", leftovers(&out));
    };

    // Another shard count: the parts of 4 are not those of 2 or 3.
    let third = part(&out, 0, 3, "rlp").display().to_string();
    import(&["--merge-shards", "3"], &sources, &out).refused(&[&third, "missing"]);
    for k in 0..2 {
        for ext in ["rlp", "rlm"] {
            std::fs::copy(part(&out, k, 4, ext), part(&out, k, 2, ext)).expect("copy");
        }
    }
    let of_two = part(&out, 0, 2, "rlm").display().to_string();
    import(&["--merge-shards", "2"], &sources, &out)
        .refused(&[&of_two, "other sources, options or shard count"]);
    untouched("another count");

    // Other sources: one post differs.
    let other = dir.join("other");
    std::fs::create_dir_all(&other).expect("dir");
    let bumped = write_sources(&other, 5.0);
    let map0 = part(&out, 0, 4, "rlm").display().to_string();
    import(&["--merge-shards", "4"], &bumped, &out).refused(&[
        &map0,
        "other sources",
        "--shard 0/4",
    ]);
    // Other options: another border.
    let layout = part(&out, 0, 4, "rlp").display().to_string();
    let other_border = ["--border", "1", "--merge-shards", "4"];
    import(&other_border, &sources, &out).refused(&[&layout, "another layout", "--shard 0/4"]);
    untouched("other sources and options");

    // A part swapped for another shard's.
    let (one, three) = (part(&out, 1, 4, "rlm"), part(&out, 3, 4, "rlm"));
    let kept = read(&one);
    std::fs::copy(&three, &one).expect("swap");
    import(&["--merge-shards", "4"], &sources, &out)
        .refused(&[&one.display().to_string(), "another shard"]);
    std::fs::write(&one, kept).expect("restore");

    // A damaged record in a pyramid part: found while merging, by file and node.
    let rlp = part(&out, 3, 4, "rlp");
    let mut bytes = read(&rlp);
    let at = bytes.len() - 100;
    bytes[at] ^= 0x40;
    std::fs::write(&rlp, &bytes).expect("damage");
    import(&["--merge-shards", "4"], &sources, &out).refused(&[&rlp.display().to_string(), "node"]);
    // A damaged header.
    bytes[at] ^= 0x40;
    bytes[40] ^= 0x01;
    std::fs::write(&rlp, &bytes).expect("damage");
    import(&["--merge-shards", "4"], &sources, &out)
        .refused(&[&rlp.display().to_string(), "--shard 3/4"]);
    untouched("damaged parts");
}
