//! Progress of long jobs on stderr, for every command and backend. On a terminal: a bar with the
//! elapsed time and an estimate of the time left (indicatif). Without one (a batch job's log,
//! CI, a pipe): a plain line at every tenth of the work, when the stage changes, and at least
//! every minute while it moves, so that a job run without a terminal still says how far it is
//! and how long it will take.
//!
//! | constructor | what |
//! |---|---|
//! | [`Progress::new`] | `show`, a label (`rendering`), the unit counted (`rows`) and the length |
//! | [`Progress::hidden`] | nothing is printed (`--quiet`, library callers) |

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How often a plain progress line is printed at the latest while the work moves.
const LINE_EVERY: Duration = Duration::from_secs(60);

/// A progress report; cheap to clone (clones report the same progress).
#[derive(Clone)]
pub struct Progress {
    mode: Arc<Mode>,
}

enum Mode {
    Hidden,
    Bar(ProgressBar),
    Lines(Mutex<Lines>),
}

/// The state of plain-line progress.
struct Lines {
    label: String,
    unit: String,
    msg: String,
    len: u64,
    pos: u64,
    start: Instant,
    last: Instant,
    /// The tenth of the work last reported (`None`: nothing printed yet).
    tenth: Option<u64>,
}

impl Progress {
    /// Progress of `len` `unit`s (e.g. 800 `rows`) under `label` (e.g. `rendering`); a bar on
    /// a terminal, plain lines otherwise, nothing when `show` is false.
    pub fn new(show: bool, label: &str, unit: &str, len: u64) -> Progress {
        let mode = if !show {
            Mode::Hidden
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(len);
            let template = format!(
                "{{msg:>12}} [{{bar:30}}] {{pos}}/{{len}} {}, {{elapsed}} (about {{eta}} left)",
                unit.replace(['{', '}'], "")
            );
            bar.set_style(
                ProgressStyle::with_template(&template)
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            bar.set_message(label.to_string());
            bar.enable_steady_tick(Duration::from_millis(500));
            Mode::Bar(bar)
        } else {
            Mode::Lines(Mutex::new(Lines::new(label, unit, len)))
        };
        Progress {
            mode: Arc::new(mode),
        }
    }

    /// A progress report that prints nothing.
    pub fn hidden() -> Progress {
        Progress {
            mode: Arc::new(Mode::Hidden),
        }
    }

    /// Whether anything is printed.
    pub fn is_hidden(&self) -> bool {
        matches!(*self.mode, Mode::Hidden)
    }

    /// `n` more units done.
    pub fn inc(&self, n: u64) {
        match &*self.mode {
            Mode::Hidden => {}
            Mode::Bar(b) => b.inc(n),
            Mode::Lines(l) => {
                let mut l = lock(l);
                l.pos = l.pos.saturating_add(n);
                l.maybe_print(false);
            }
        }
    }

    /// `k` units done.
    pub fn set_position(&self, k: u64) {
        match &*self.mode {
            Mode::Hidden => {}
            Mode::Bar(b) => b.set_position(k),
            Mode::Lines(l) => {
                let mut l = lock(l);
                l.pos = k;
                l.maybe_print(false);
            }
        }
    }

    /// The work is `n` units in all.
    pub fn set_length(&self, n: u64) {
        match &*self.mode {
            Mode::Hidden => {}
            Mode::Bar(b) => b.set_length(n),
            Mode::Lines(l) => lock(l).len = n,
        }
    }

    /// The stage or item being worked on (a line is printed when it changes).
    pub fn set_message(&self, msg: &str) {
        match &*self.mode {
            Mode::Hidden => {}
            Mode::Bar(b) => b.set_message(msg.to_string()),
            Mode::Lines(l) => {
                let mut l = lock(l);
                if l.msg != msg {
                    l.msg = msg.to_string();
                    l.maybe_print(true);
                }
            }
        }
    }

    /// The item being worked on (an image's name): shown on the bar, and in the next plain line
    /// without printing one of its own.
    pub fn set_item(&self, item: &str) {
        match &*self.mode {
            Mode::Hidden => {}
            Mode::Bar(b) => b.set_message(item.to_string()),
            Mode::Lines(l) => lock(l).msg = item.to_string(),
        }
    }

    /// The work is over: the bar is cleared; plain lines end with the total time.
    pub fn finish(&self) {
        match &*self.mode {
            Mode::Hidden => {}
            Mode::Bar(b) => b.finish_and_clear(),
            Mode::Lines(l) => {
                let l = lock(l);
                if l.tenth.is_some() && l.len == 0 {
                    eprintln!("{}: done in {}", l.label, duration(l.start.elapsed()));
                } else if l.tenth.is_some() {
                    eprintln!(
                        "{}: done, {} {} in {}",
                        l.label,
                        l.pos,
                        l.unit,
                        duration(l.start.elapsed())
                    );
                }
            }
        }
    }
}

fn lock(l: &Mutex<Lines>) -> std::sync::MutexGuard<'_, Lines> {
    l.lock().unwrap_or_else(|e| e.into_inner())
}

impl Lines {
    fn new(label: &str, unit: &str, len: u64) -> Lines {
        let now = Instant::now();
        Lines {
            label: label.to_string(),
            unit: unit.to_string(),
            msg: String::new(),
            len,
            pos: 0,
            start: now,
            last: now,
            tenth: None,
        }
    }

    /// Print a line when the work crossed into a new tenth, when `changed` (a new stage), or
    /// when a minute passed since the last line.
    fn maybe_print(&mut self, changed: bool) {
        let tenth = (self.pos.min(self.len) * 10)
            .checked_div(self.len)
            .unwrap_or(0);
        let now = Instant::now();
        let due = changed
            || self.tenth.is_none_or(|t| tenth > t)
            || now.duration_since(self.last) >= LINE_EVERY;
        if !due {
            return;
        }
        self.tenth = Some(tenth);
        self.last = now;
        eprintln!("{}", self.line(now.duration_since(self.start)));
    }

    fn line(&self, elapsed: Duration) -> String {
        let msg = if self.msg.is_empty() {
            String::new()
        } else {
            format!(" ({})", self.msg)
        };
        if self.len == 0 {
            return format!("{}{msg}: {} elapsed", self.label, duration(elapsed));
        }
        let pos = self.pos.min(self.len);
        let mut s = format!(
            "{}{msg}: {pos}/{} {} ({} %), {} elapsed",
            self.label,
            self.len,
            self.unit,
            pos * 100 / self.len,
            duration(elapsed)
        );
        if pos > 0 && pos < self.len {
            let left = elapsed.mul_f64((self.len - pos) as f64 / pos as f64);
            s.push_str(&format!(", about {} left", duration(left)));
        }
        s
    }
}

/// A duration as a person reads it: `42 s`, `3 min 05 s`, `2 h 07 min`.
pub fn duration(d: Duration) -> String {
    let s = d.as_secs();
    if s < 60 {
        format!("{s} s")
    } else if s < 3600 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{} h {:02} min", s / 3600, (s % 3600) / 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(len: u64) -> Lines {
        Lines::new("rendering", "rows", len)
    }

    #[test]
    fn a_line_says_how_far_and_how_long_is_left() {
        let mut l = lines(800);
        l.pos = 200;
        assert_eq!(
            l.line(Duration::from_secs(90)),
            "rendering: 200/800 rows (25 %), 1 min 30 s elapsed, about 4 min 30 s left"
        );
        l.msg = "SIFT".into();
        l.pos = 800;
        assert_eq!(
            l.line(Duration::from_secs(4000)),
            "rendering (SIFT): 800/800 rows (100 %), 1 h 06 min elapsed"
        );
        l.len = 0;
        assert_eq!(
            l.line(Duration::from_secs(3)),
            "rendering (SIFT): 3 s elapsed"
        );
    }

    #[test]
    fn lines_come_at_each_tenth_not_at_each_unit() {
        let mut l = lines(1000);
        let mut printed = 0;
        for _ in 0..1000 {
            l.pos += 1;
            let before = l.tenth;
            l.maybe_print(false);
            if l.tenth != before {
                printed += 1;
            }
        }
        // The first unit, then each tenth from 1/10 to 10/10.
        assert_eq!(printed, 11);
        assert_eq!(l.tenth, Some(10));
    }
}
