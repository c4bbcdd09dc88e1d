//! A killed import leaves the previous cache intact: the real `ridgeline
//! import` binary is killed while it writes its new file, and the old cache
//! must still open, verify and hold exactly its old bytes.

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use ridgeline::pyramid::{Pyramid, FILE_NAME};
use testkit::cli::{Ridgeline, Run};
use testkit::fresh_dir;

fn import(size: u32, out: &Path) -> Run {
    let ridgeline = Ridgeline::new(env!("CARGO_BIN_EXE_ridgeline"));
    ridgeline.args(["import", "--synthetic", &size.to_string(), "--out"]).arg(out)
}

/// The temporary files an import has left beside the pyramid.
fn temporaries(dir: &Path) -> Vec<std::path::PathBuf> {
    let prefix = format!("{FILE_NAME}.tmp-");
    std::fs::read_dir(dir)
        .expect("list cache")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .map(|e| e.path())
        .collect()
}

/// Kills the import if the test fails before it does.
struct KillOnDrop(std::process::Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn killing_an_import_midway_keeps_the_previous_cache() {
    let cache = fresh_dir("kill-import");
    import(300, &cache).ok();
    let old_bytes = std::fs::read(cache.join(FILE_NAME)).expect("old cache");
    let old_info = Pyramid::open(&cache).expect("old cache opens").info().clone();

    // 4096^2 samples make a 104 MB pyramid: seconds of building, then a write
    // and flush far longer than the few milliseconds between polls.
    let mut child = KillOnDrop(import(4096, &cache).spawn(Stdio::null(), Stdio::null()).child);
    let child = &mut child.0;
    let started = Instant::now();
    while temporaries(&cache).is_empty() {
        if let Some(status) = child.try_wait().expect("poll import") {
            panic!("the import ended ({status}) before it began writing; make its input larger");
        }
        assert!(started.elapsed() < Duration::from_secs(300), "the import never began writing");
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("kill the import");
    let status = child.wait().expect("reap the import");
    assert!(!status.success(), "the import finished before it was killed");
    assert_eq!(temporaries(&cache).len(), 1, "the kill came mid-write: its temporary file remains");

    assert_eq!(std::fs::read(cache.join(FILE_NAME)).expect("cache after kill"), old_bytes);
    let reopened = Pyramid::open(&cache).expect("the old cache still opens");
    reopened.verify().expect("and verifies");
    assert_eq!(reopened.info(), &old_info);

    // The next import clears the dead import's temporary file.
    import(200, &cache).ok();
    assert!(temporaries(&cache).is_empty(), "stale temporary left behind");
    assert_eq!(Pyramid::open(&cache).expect("new cache").info().layout.posts, [200, 200]);
}
