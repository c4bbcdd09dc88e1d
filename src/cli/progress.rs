//! The progress bar the subcommands show while they build pyramids.

use indicatif::{ProgressBar, ProgressStyle};
use ridgeline::pyramid::Progress;

pub struct Bar(ProgressBar);

impl Bar {
    pub fn new() -> Self {
        let style = ProgressStyle::with_template(
            "{msg:>18} [{bar:40}] {percent:>3}% {elapsed} (ETA {eta})",
        )
        .expect("the template is valid")
        .progress_chars("=> ");
        Bar(ProgressBar::new(0).with_style(style))
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl Progress for Bar {
    fn phase(&self, name: &str, total: u64) {
        self.0.set_message(name.to_string());
        self.0.set_length(total);
        self.0.set_position(0);
    }

    fn advance(&self, units: u64) {
        self.0.inc(units);
    }
}
