//! A spinner on stderr for long steps; silent when stderr is not a terminal.

use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

pub struct Steps {
    bar: ProgressBar,
    started: Instant,
}

impl Steps {
    pub fn new(title: &str) -> Steps {
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} {prefix}: {msg} [{elapsed}]")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_prefix(title.to_string());
        bar.enable_steady_tick(Duration::from_millis(120));
        Steps {
            bar,
            started: Instant::now(),
        }
    }

    pub fn step(&self, message: &str) {
        self.bar.set_message(message.to_string());
    }

    /// Seconds since the spinner started.
    pub fn finish(self) -> f64 {
        self.bar.finish_and_clear();
        self.started.elapsed().as_secs_f64()
    }
}

/// A progress bar over a known number of items; silent when stderr is not a terminal.
pub struct Bar {
    bar: ProgressBar,
}

impl Bar {
    pub fn new(title: &str, total: u64) -> Bar {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template(
                "{prefix}: [{bar:30}] {pos}/{len} {msg} [{elapsed} < {eta}]",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_prefix(title.to_string());
        Bar { bar }
    }

    pub fn inc(&self) {
        self.bar.inc(1);
    }

    /// A line on stderr above the bar (always printed, terminal or not).
    pub fn println(&self, line: &str) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    pub fn finish(self) {
        self.bar.finish_and_clear();
    }
}
