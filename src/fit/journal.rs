//! What a fit tells as it runs: progress lines, stamped with the seconds since the fit
//! started; the notes that the material file and the report carry; and the degree log (one
//! line per direction and degree tried). Every stage writes through the fitter's one
//! [`Journal`]; the stage timings live beside the solve counts in [`super::FitStats`]
//! ([`super::FitStats::time_stage`]).

use std::time::Instant;

/// The fit's progress lines, notes and degree log.
pub(super) struct Journal<'a> {
    progress: &'a mut dyn FnMut(&str),
    start: Instant,
    notes: Vec<String>,
    degree_log: Vec<String>,
}

impl<'a> Journal<'a> {
    /// A journal that starts at `start` with `notes` already taken (the dataset's and the
    /// set-up's).
    pub(super) fn new(
        progress: &'a mut dyn FnMut(&str),
        start: Instant,
        notes: Vec<String>,
    ) -> Self {
        Journal {
            progress,
            start,
            notes,
            degree_log: Vec::new(),
        }
    }

    /// A progress line, `[   12.3 s] msg`.
    pub(super) fn say(&mut self, msg: &str) {
        let t = self.start.elapsed().as_secs_f64();
        (self.progress)(&format!("[{t:7.1} s] {msg}"));
    }

    /// A note for the material file's `[fit] notes` and the report.
    pub(super) fn note(&mut self, note: String) {
        self.notes.push(note);
    }

    /// Drops the notes that start with `prefix`: a warning that a later stage made untrue, or
    /// one about to be given again.
    pub(super) fn drop_notes(&mut self, prefix: &str) {
        self.notes.retain(|n| !n.starts_with(prefix));
    }

    /// A line of the degree log.
    pub(super) fn degree(&mut self, line: String) {
        self.degree_log.push(line);
    }

    /// A line of the degree log, said as progress too.
    pub(super) fn log_degree(&mut self, line: String) {
        self.say(&line);
        self.degree(line);
    }

    /// Says and notes a change a rule made to the law (`None`: no change); whether it did.
    pub(super) fn law_note(&mut self, note: Option<String>) -> bool {
        let Some(note) = note else { return false };
        self.say(&note);
        self.note(note);
        true
    }

    /// Seconds since the fit started.
    pub(super) fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// The notes and the degree log, for the fit's result.
    pub(super) fn finish(self) -> (Vec<String>, Vec<String>) {
        (self.notes, self.degree_log)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_stamped_and_notes_kept_in_order() {
        let mut lines = Vec::new();
        let mut sink = |l: &str| lines.push(l.to_string());
        let mut j = Journal::new(&mut sink, Instant::now(), vec!["from the data".into()]);
        j.say("warp stage");
        j.note("a choice".into());
        j.degree("warp: degree 1".into());
        let (notes, degrees) = j.finish();
        assert_eq!(notes, ["from the data", "a choice"]);
        assert_eq!(degrees, ["warp: degree 1"]);
        assert_eq!(lines.len(), 1);
        assert!(
            lines[0].starts_with('[') && lines[0].ends_with("s] warp stage"),
            "{lines:?}"
        );
    }
}
