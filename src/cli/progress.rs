//! The progress the subcommands show while they build pyramids: a bar on a
//! terminal; elsewhere (a batch job's log: shards on a cluster, CI) one
//! line as each phase ends, with its time, and a line at every quarter of
//! a long phase with its ETA, so a log says where the time went.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use ridgeline::pyramid::Progress;

pub enum Bar {
    /// A bar redrawn in place on a terminal.
    Terminal(ProgressBar),
    /// Lines on a log.
    Log(LogLines),
}

/// The phase a log is in.
pub struct LogLines {
    phase: Mutex<Option<Phase>>,
    done: AtomicU64,
    started: Instant,
}

struct Phase {
    name: String,
    total: u64,
    started: Instant,
    /// Quarters of the phase reported so far.
    quarters: u64,
}

/// Phases shorter than this print no quarter lines.
const QUIET_SECONDS: f64 = 10.0;

impl Bar {
    pub fn new() -> Self {
        if !std::io::stderr().is_terminal() {
            let phase = Mutex::new(None);
            return Bar::Log(LogLines { phase, done: AtomicU64::new(0), started: Instant::now() });
        }
        let style = ProgressStyle::with_template(
            "{msg:>18} [{bar:40}] {percent:>3}% {elapsed} (ETA {eta})",
        )
        .expect("the template is valid")
        .progress_chars("=> ");
        Bar::Terminal(ProgressBar::new(0).with_style(style))
    }

    /// Removes the bar from the terminal; on a log, ends the last phase.
    pub fn finish(&self) {
        match self {
            Bar::Terminal(bar) => bar.finish_and_clear(),
            Bar::Log(log) => log.end_phase(),
        }
    }
}

impl LogLines {
    fn end_phase(&self) {
        let mut phase = self.phase.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(ended) = phase.take() {
            eprintln!(
                "{:>18}: done in {:.1} s ({:.1} s in all)",
                ended.name,
                ended.started.elapsed().as_secs_f64(),
                self.started.elapsed().as_secs_f64()
            );
        }
    }
}

impl Progress for Bar {
    fn phase(&self, name: &str, total: u64) {
        match self {
            Bar::Terminal(bar) => {
                bar.set_message(name.to_string());
                bar.set_length(total);
                bar.set_position(0);
            }
            Bar::Log(log) => {
                log.end_phase();
                log.done.store(0, Ordering::Relaxed);
                let phase =
                    Phase { name: name.into(), total, started: Instant::now(), quarters: 0 };
                *log.phase.lock().unwrap_or_else(|e| e.into_inner()) = Some(phase);
            }
        }
    }

    fn advance(&self, units: u64) {
        match self {
            Bar::Terminal(bar) => bar.inc(units),
            Bar::Log(log) => {
                let done = log.done.fetch_add(units, Ordering::Relaxed) + units;
                let mut phase = log.phase.lock().unwrap_or_else(|e| e.into_inner());
                let Some(phase) = phase.as_mut() else { return };
                let quarters = (done * 4).checked_div(phase.total).unwrap_or(0).min(3);
                let seconds = phase.started.elapsed().as_secs_f64();
                if quarters > phase.quarters && seconds > QUIET_SECONDS {
                    phase.quarters = quarters;
                    let eta = seconds * (phase.total as f64 / done as f64 - 1.0);
                    eprintln!(
                        "{:>18}: {}% in {seconds:.0} s, ETA {eta:.0} s",
                        phase.name,
                        quarters * 25
                    );
                }
            }
        }
    }
}
