//! The `ridgeline` binary run as a user runs it: one runner that every CLI
//! test shares, so that running, waiting and the failure message (the
//! arguments and the whole stderr) are written once.
//!
//! Cargo sets `CARGO_BIN_EXE_ridgeline` only while it compiles an
//! integration test, so the test passes the path in:
//! `Ridgeline::new(env!("CARGO_BIN_EXE_ridgeline"))`.

use std::ffi::OsStr;
use std::process::{Child, Command, ExitStatus, Output, Stdio};

/// The binary under test.
#[derive(Clone, Copy, Debug)]
pub struct Ridgeline {
    exe: &'static str,
}

impl Ridgeline {
    /// The binary at `exe` (a test's `env!("CARGO_BIN_EXE_ridgeline")`).
    pub const fn new(exe: &'static str) -> Self {
        Self { exe }
    }

    /// A run with `args`, not started yet: add arguments, then
    /// [`Run::ok`], [`Run::refused`], [`Run::output`] or [`Run::spawn`].
    pub fn args<I, S>(&self, args: I) -> Run
    where
        I: IntoIterator<Item = S>,
        S: AsRef<OsStr>,
    {
        Run { command: Command::new(self.exe) }.args(args)
    }
}

/// One invocation of the binary being put together.
#[derive(Debug)]
pub struct Run {
    command: Command,
}

impl Run {
    /// Adds one argument (a path, typically).
    pub fn arg(mut self, arg: impl AsRef<OsStr>) -> Self {
        self.command.arg(arg);
        self
    }

    /// Adds arguments.
    pub fn args<I, S>(mut self, args: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: AsRef<OsStr>,
    {
        self.command.args(args);
        self
    }

    /// Runs to the end, however it exits.
    pub fn output(mut self) -> Ran {
        let what = describe(&self.command);
        let output = self.command.output().unwrap_or_else(|e| panic!("start `{what}`: {e}"));
        Ran { what, output }
    }

    /// Runs to the end and insists it succeeded.
    pub fn ok(self) -> Ran {
        self.output().ok()
    }

    /// Runs to the end and insists it failed saying each of `says`.
    pub fn refused(self, says: &[&str]) -> Ran {
        self.output().refused(says)
    }

    /// Starts it in the background with these standard output and error.
    pub fn spawn(mut self, stdout: Stdio, stderr: Stdio) -> Running {
        let what = describe(&self.command);
        self.command.stdin(Stdio::null()).stdout(stdout).stderr(stderr);
        let child = self.command.spawn().unwrap_or_else(|e| panic!("start `{what}`: {e}"));
        Running { what, child }
    }
}

/// A run started in the background.
#[derive(Debug)]
pub struct Running {
    what: String,
    /// The process, to read from, poll or kill.
    pub child: Child,
}

impl Running {
    /// Waits for it to end and collects what it said (the streams left
    /// piped and not taken).
    pub fn finish(self) -> Ran {
        let what = self.what;
        let output = self.child.wait_with_output().unwrap_or_else(|e| panic!("wait `{what}`: {e}"));
        Ran { what, output }
    }
}

/// A finished run: its exit status and what it printed.
#[derive(Debug)]
pub struct Ran {
    what: String,
    /// The exit status and both streams, as captured.
    pub output: Output,
}

impl Ran {
    /// Whether it exited with success.
    pub fn success(&self) -> bool {
        self.status().success()
    }

    /// Its exit status.
    pub fn status(&self) -> ExitStatus {
        self.output.status
    }

    /// Its standard output, as text.
    pub fn stdout(&self) -> String {
        String::from_utf8_lossy(&self.output.stdout).into_owned()
    }

    /// Its standard error, as text.
    pub fn stderr(&self) -> String {
        String::from_utf8_lossy(&self.output.stderr).into_owned()
    }

    /// Insists it succeeded: a failure names the arguments and shows stderr.
    #[track_caller]
    pub fn ok(self) -> Self {
        assert!(self.success(), "`{}` failed ({}):\n{}", self.what, self.status(), self.stderr());
        self
    }

    /// Insists it failed, saying each of `says` on stderr, without a panic
    /// (bad input is refused by name, never by a crash).
    #[track_caller]
    pub fn refused(self, says: &[&str]) -> Self {
        let stderr = self.stderr();
        assert!(!self.success(), "`{}` succeeded:\n{stderr}", self.what);
        for text in says {
            assert!(stderr.contains(text), "`{}`: {stderr:?} does not say {text:?}", self.what);
        }
        assert!(!stderr.contains("panicked"), "`{}` panicked:\n{stderr}", self.what);
        self
    }
}

/// `ridgeline <args>` as a failure message shows it.
fn describe(command: &Command) -> String {
    let args = command.get_args().map(|a| a.to_string_lossy().into_owned());
    std::iter::once("ridgeline".to_string()).chain(args).collect::<Vec<_>>().join(" ")
}
