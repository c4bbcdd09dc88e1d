//! `ridgeline import` and `ridgeline info` as a user runs them.

mod pyramid_common;

use std::path::Path;
use std::process::{Command, Output};

use pyramid_common::scratch_dir;
use ridgeline::pyramid::FILE_NAME;

fn ridgeline(args: &[&str], cache: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ridgeline")).args(args).arg(cache).output().expect("run ridgeline")
}

#[test]
fn info_json_describes_an_imported_cache() {
    let cache = scratch_dir("cli-info");
    let imported = ridgeline(&["import", "--synthetic", "257", "--node-size", "32", "--border", "1", "--out"], &cache);
    assert!(imported.status.success(), "{}", String::from_utf8_lossy(&imported.stderr));
    let info = ridgeline(&["info", "--json"], &cache);
    assert!(info.status.success(), "{}", String::from_utf8_lossy(&info.stderr));
    let json: serde_json::Value = serde_json::from_slice(&info.stdout).expect("info --json prints JSON");
    assert_eq!(json["levels"], 4, "256 cells need 32 << 3");
    assert_eq!(json["node_size"], 32);
    assert_eq!(json["samples"], serde_json::json!([257, 257]));
    assert_eq!(json["extent"]["east_m"], 256.0 * 90.0);
    assert!(json["georef"]["west"].is_null(), "a local grid has no degrees");
    let deltas = json["delta_per_level"].as_array().expect("deltas");
    assert_eq!(deltas.len(), 4);
    assert_eq!(deltas[0], 0.0);
    assert!(deltas[1..].iter().all(|d| d.as_f64().expect("number") > 0.0));
    let (lo, hi) = (json["height_min"].as_f64().expect("min"), json["height_max"].as_f64().expect("max"));
    assert!(lo < hi);
    assert_eq!(json["voids_filled"], 0);

    let table = ridgeline(&["info"], &cache);
    let text = String::from_utf8_lossy(&table.stdout);
    assert!(table.status.success() && text.contains("257 x 257") && text.contains("4 levels"), "{text}");
}

#[test]
fn info_refuses_a_damaged_cache_naming_the_file() {
    let cache = scratch_dir("cli-damaged");
    assert!(ridgeline(&["import", "--synthetic", "100", "--out"], &cache).status.success());
    let path = cache.join(FILE_NAME);
    let mut bytes = std::fs::read(&path).expect("read");
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x10;
    std::fs::write(&path, bytes).expect("damage");
    let info = ridgeline(&["info"], &cache);
    let stderr = String::from_utf8_lossy(&info.stderr);
    assert!(!info.status.success());
    assert!(stderr.contains(&path.display().to_string()) && stderr.contains("damaged"), "{stderr}");
}

#[test]
fn import_refuses_absurd_sizes_before_allocating() {
    let cache = scratch_dir("cli-absurd");
    let out = ridgeline(&["import", "--synthetic", "4000000000", "--out"], &cache);
    assert!(!out.status.success());
    let out = ridgeline(&["import", "--synthetic", "100", "--node-size", "0", "--out"], &cache);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("node size"));
}
