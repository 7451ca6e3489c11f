//! How a local batch reports as fabrics finish: the summary files rewritten at most every few
//! seconds (a rewrite reads every fabric's material, so one per fabric makes a large library
//! quadratic), and an estimate of the time left from the fabrics run so far.

use std::time::{Duration, Instant};

/// Shortest time between two rewrites of summary.csv and index.html while fabrics finish.
pub const SUMMARY_EVERY: Duration = Duration::from_secs(5);

/// A rewrite waits at least this many times as long as the last one took, so that writing the
/// summary of a large library never takes more than a small share of the batch.
const SUMMARY_COST_FACTOR: u32 = 10;

/// Fabrics that must have run (not skipped) for the time left to be estimated.
pub const ESTIMATE_AFTER: usize = 3;

/// When the summary files are due again.
pub struct Pace {
    last: Instant,
    gap: Duration,
}

impl Pace {
    /// A pace whose first rewrite is due [`SUMMARY_EVERY`] after `now` (the batch writes the
    /// summary as it starts).
    pub fn new(now: Instant) -> Self {
        Pace {
            last: now,
            gap: SUMMARY_EVERY,
        }
    }

    /// Whether a rewrite is due at `now`.
    pub fn due(&self, now: Instant) -> bool {
        now.duration_since(self.last) >= self.gap
    }

    /// Records a rewrite that ended at `now` and took `took`.
    pub fn wrote(&mut self, now: Instant, took: Duration) {
        self.last = now;
        self.gap = SUMMARY_EVERY.max(took * SUMMARY_COST_FACTOR);
    }
}

/// The clause on the time left after a fabric finishes, `left` fabrics to go, `jobs` side by
/// side: the median wall time of the fabrics run so far (`walls`, seconds; skipped ones are not
/// counted) for each round of `jobs`, or, when it says more, the batch's own pace (`pace`:
/// seconds it has taken per finished fabric, which holds what a fabric's wall time does not:
/// writing the summary, moving folders). Empty when none are left.
pub fn time_left(walls: &[f64], left: usize, jobs: usize, pace: f64) -> String {
    if left == 0 {
        return String::new();
    }
    if walls.len() < ESTIMATE_AFTER {
        return format!(
            ", time left not estimated until {ESTIMATE_AFTER} fabrics have run ({} so far)",
            walls.len()
        );
    }
    let mut sorted = walls.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    };
    let rounds = left.div_ceil(jobs.max(1));
    let plural = if left == 1 { "" } else { "s" };
    let (by_median, by_pace) = (median * rounds as f64, pace * left as f64);
    if by_pace > by_median {
        format!(
            ", about {} left ({left} fabric{plural} at the {pace:.3} s a fabric this batch has taken so far)",
            duration(by_pace)
        )
    } else {
        format!(
            ", about {} left ({left} fabric{plural} at the median {median:.1} s of the {n} run so far)",
            duration(by_median)
        )
    }
}

/// "40 s", "12 min", "3.5 h".
pub fn duration(seconds: f64) -> String {
    if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else if seconds < 7200.0 {
        format!("{:.0} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_is_rewritten_at_most_every_few_seconds() {
        let t0 = Instant::now();
        let mut pace = Pace::new(t0);
        assert!(!pace.due(t0 + Duration::from_millis(100)));
        assert!(pace.due(t0 + SUMMARY_EVERY));
        // a rewrite that took 2 s waits 20 s for the next
        let t1 = t0 + SUMMARY_EVERY;
        pace.wrote(t1, Duration::from_secs(2));
        assert!(!pace.due(t1 + SUMMARY_EVERY));
        assert!(pace.due(t1 + Duration::from_secs(20)));
    }

    #[test]
    fn the_time_left_comes_from_the_median_fabric() {
        assert!(time_left(&[1.0, 2.0], 5, 1, 1.0).contains("not estimated until 3"));
        assert_eq!(time_left(&[1.0, 2.0, 3.0], 0, 1, 1.0), "");
        // one slow outlier does not move the median: 10 left at 2 s, two at a time
        let s = time_left(&[1.0, 2.0, 600.0], 10, 2, 0.5);
        assert!(s.contains("about 10 s left"), "{s}");
        assert!(s.contains("median 2.0 s of the 3 run"), "{s}");
        assert!(time_left(&[100.0; 4], 200, 1, 1.0).contains("about 5.6 h left"));
        // fabrics that take no time, in a batch that takes 10 ms for each
        let s = time_left(&[1e-4; 5], 3000, 1, 0.01);
        assert!(
            s.contains("about 30 s left") && s.contains("0.010 s a fabric"),
            "{s}"
        );
    }
}
