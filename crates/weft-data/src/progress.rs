//! The progress bar of `weft data generate` on stderr: frames simulated out of the
//! total, frames per second and the time left, with diverged or failed sequences
//! printed above the bar as they happen. Hidden when stderr is not a terminal
//! (indicatif's default), so logs of cluster jobs stay clean.

use indicatif::{ProgressBar, ProgressStyle};

use crate::generate::Progress;

/// An indicatif bar implementing [`Progress`].
pub struct FrameBar {
    bar: ProgressBar,
}

impl Default for FrameBar {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameBar {
    /// A bar on stderr, not yet started.
    pub fn new() -> Self {
        let bar = ProgressBar::new(0);
        let style = ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} frames ({per_sec}, ETA {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.set_style(style);
        FrameBar { bar }
    }
}

impl Progress for FrameBar {
    fn start(&self, total: u64, sequences: usize, kept: usize) {
        self.bar.set_length(total);
        self.bar.set_message(if kept > 0 {
            format!("{sequences} sequences ({kept} already done)")
        } else {
            format!("{sequences} sequences")
        });
        self.bar.reset_eta();
    }

    fn frame(&self) {
        self.bar.inc(1);
    }

    fn message(&self, text: &str) {
        self.bar.println(text);
        if self.bar.is_hidden() {
            eprintln!("{text}");
        }
    }

    fn finish(&self) {
        self.bar.finish();
    }
}
