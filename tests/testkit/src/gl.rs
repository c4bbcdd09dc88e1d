//! What the GL test binaries share: one context at a time, the loud skips of
//! optional backends (OSMesa, a window) and their `RIDGELINE_REQUIRE_*`
//! switches, an Xvfb server of our own, and child processes of the running
//! test binary (winit allows one event loop per process; Mesa's overrides
//! must be set before the driver loads).

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Mutex, MutexGuard};

use ridgeline::gl::{probe, GlError};

/// llvmpipe already uses every core; contexts take turns.
static SERIAL: Mutex<()> = Mutex::new(());

/// Holds the GL turn until dropped (a test that panicked does not poison it).
pub fn take_turn() -> MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Whether `var` is set to 1 (CI sets the RIDGELINE_REQUIRE_* switches).
pub fn required(var: &str) -> bool {
    std::env::var(var).is_ok_and(|value| value == "1")
}

/// True, after saying so loudly, when `error` is libOSMesa missing and
/// RIDGELINE_REQUIRE_OSMESA=1 is not set: the caller then skips `test`.
pub fn skip_for_missing_osmesa(test: &str, error: &GlError) -> bool {
    let GlError::LibraryMissing { library, reason } = error else { return false };
    if required("RIDGELINE_REQUIRE_OSMESA") {
        return false;
    }
    eprintln!(
        "\n*** SKIPPED {test}: {library} missing ({reason}).\n\
         *** Install libosmesa6; RIDGELINE_REQUIRE_OSMESA=1 makes this a failure.\n"
    );
    true
}

/// An Xvfb server this test started, killed on drop.
pub struct Xvfb {
    server: Child,
    display: String,
}

impl Xvfb {
    /// Starts Xvfb on a free display number (-displayfd prints it when the
    /// server is ready), or None when Xvfb is not installed.
    pub fn start() -> Option<Xvfb> {
        let spawned = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "320x240x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn();
        let mut server = match spawned {
            Ok(server) => server,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None,
            Err(e) => panic!("Xvfb is installed but did not start: {e}"),
        };
        let mut line = String::new();
        let stdout = server.stdout.take().expect("piped stdout");
        BufReader::new(stdout).read_line(&mut line).expect("read Xvfb's display number");
        let number: u32 = line.trim().parse().unwrap_or_else(|_| {
            let _ = server.kill();
            panic!("Xvfb printed {line:?} instead of a display number")
        });
        Some(Xvfb { server, display: format!(":{number}") })
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// The X display a window test uses, and the server behind it if we started one.
pub struct WindowDisplay {
    pub display: String,
    _server: Option<Xvfb>,
}

/// A display for `test`'s windows: the developer's own when it answers, else
/// an Xvfb of our own. None (after saying so loudly) when neither exists and
/// RIDGELINE_REQUIRE_WINDOW=1 is not set; a panic when it is.
pub fn window_display(test: &str) -> Option<WindowDisplay> {
    let existing =
        std::env::var("DISPLAY").ok().filter(|d| !d.is_empty() && probe::display_answers().is_ok());
    if let Some(display) = existing {
        return Some(WindowDisplay { display, _server: None });
    }
    match Xvfb::start() {
        Some(server) => {
            Some(WindowDisplay { display: server.display.clone(), _server: Some(server) })
        }
        None if !required("RIDGELINE_REQUIRE_WINDOW") => {
            eprintln!(
                "\n*** SKIPPED {test}: no display answers and Xvfb is not installed.\n\
                 *** Install xvfb; RIDGELINE_REQUIRE_WINDOW=1 makes this a failure.\n"
            );
            None
        }
        None => panic!("RIDGELINE_REQUIRE_WINDOW=1 but no display answers and Xvfb is missing"),
    }
}

/// A command running only the ignored test `name` of this test binary, in a
/// new process without Wayland (windows go to the X display given).
pub fn child_test(name: &str) -> Command {
    let mut command = Command::new(std::env::current_exe().expect("test binary path"));
    command
        .args([name, "--exact", "--ignored", "--nocapture", "--test-threads=1"])
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET");
    command
}

/// Runs a [`child_test`] command, prints what it said, and checks it passed
/// exactly one test.
pub fn run_child(command: &mut Command, what: &str) -> Output {
    let output = command.output().expect("run the child test");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("child ({what}):\n{stdout}{stderr}");
    assert!(output.status.success(), "child test ({what}) failed");
    assert!(stdout.contains("1 passed"), "the child ({what}) ran no test");
    output
}
