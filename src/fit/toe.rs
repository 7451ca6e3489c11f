//! Toe compensation: where each tensile curve's zero elongation lies.
//!
//! A hand-mounted strip starts slack (the force stays near zero, or creeps up, until the strip
//! is taut) or preloaded (a force at zero elongation). Both shift the elongation axis. Two
//! rules look for the toe; the first that finds one gives it.
//!
//! **The hinge rule.** The start of the curve (the points from 2 % to 40 % of the largest
//! force, widened to 60, 80 and 100 % where fewer than 8 points lie there; below 2 % a slack
//! strip creeps) is fitted twice by least squares: by a cubic through the origin, and by a
//! hinge, zero up to an elongation s and a cubic in (e − s) after it, s found by a search.
//! When the hinge fits at least ten times better (residual sum of squares) the curve has a toe
//! (a slack one only when at least two measured points lie below s: the creep must be in the
//! data). s is the tangent of the steep region extended to zero force, in the limit of a sharp
//! knee; s < 0 is a preload. A smooth curve through the origin, stiffening or not, is fitted by
//! the cubic already and keeps its zero.
//!
//! **The flat-stretch rule.** Load-cell noise hides the hinge's ten-fold gain: a cubic through
//! the origin mimics a shifted, stiffening rise over the steep region to within a few times
//! the noise. The flat points of the slack, left out above, contradict it. So every point from
//! the first up to the same cut (the creep included) is fitted by a level c (the load cell's
//! zero, which may be off) up to s and c plus a cubic in (e − s) after it, s from 0 (no slack:
//! a level and a cubic from the origin) onwards. The curve has slack s when
//! * at least two measured points lie below s;
//! * the knee at s lowers the residual sum of squares by at least 25 times the noise variance
//!   (the residual's mean square with the knee): far beyond what noise gives an extra parameter;
//! * the points below s (the last one left out: it may lie on the knee's creep) show no trend:
//!   their slope is within 4 standard errors of zero, at their own noise variance (at the
//!   same one where fewer than 8 points lie there);
//! * the knee is sharp: the rise's slope just after s is at least 0.66 of its mean slope over
//!   the rest of the window, or a level and a rise from zero slope (a smooth onset, placed
//!   where it fits best) leaves a residual sum of squares larger by the same 25 noise
//!   variances. A convex onset that is the material's own (a stiffening law whose first
//!   forces are lost in the noise) rises from a slope near zero, fails both and keeps its
//!   zero.
//!
//! The rule runs on the points up to 5 % of the largest force first, then, where it finds no
//! slack there, up to 10, 20 and 40 %: over a wide window a law that stiffens tenfold (a warp
//! whose η has a term of α 245) is no cubic, the cubic's residual hides the knee and its best
//! knee moves up the rise; the shortest window that holds enough of the rise follows it
//! (`paper_repro/zoo/README.md` counts what it finds on the lab zoo).
//!
//! The level c is allowed so that a constant offset of the load cell does not pass for a
//! trend; the forces themselves are used as measured. Under noise of 0.2 % of the largest force
//! 0.2 mm of slack is found when four points or so lie in it.

/// Forces below this fraction of the largest are a slack strip's creep, not the steep region.
pub const TOE_FLOOR: f64 = 0.02;

/// Measured points that must lie below a slack toe (the slack must be in the data).
const SLACK_POINTS: usize = 2;

/// Least gain of the flat-stretch knee, in units of the noise variance.
const SLACK_SIGNIFICANCE: f64 = 25.0;

/// Largest slope, in standard errors, of the points below a flat-stretch knee.
const SLACK_TREND: f64 = 4.0;

/// Fewest points below a knee whose own residual variance measures their noise (six degrees
/// of freedom); fewer are tested at the window's variance.
const OWN_NOISE_POINTS: usize = 8;

/// Least slope just after a flat-stretch knee, as a fraction of the rise's mean slope.
const KNEE_SLOPE: f64 = 0.66;

/// The flat-stretch rule's windows, tried in turn, each ending at the first point above this
/// fraction of the largest force (widened as [`window`] widens): a cubic cannot follow a law
/// that stiffens tenfold within the widest one, and a shorter window sees the knee.
const SLACK_WINDOWS: [f64; 4] = [0.05, 0.1, 0.2, 0.4];

/// Least-squares residual of a cubic in (e − s)₊ without a constant (points with e ≤ s
/// predicted as 0).
fn cubic_rss(pts: &[(f64, f64)], s: f64) -> f64 {
    let scale = pts.last().map_or(1.0, |p| p.0.abs().max(1e-12));
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Vector3::<f64>::zeros();
    for &(e, f) in pts {
        let x = ((e - s) / scale).max(0.0);
        let row = nalgebra::Vector3::new(x, x * x, x * x * x);
        ata += row * row.transpose();
        atb += row * f;
    }
    let Some(c) = ata.try_inverse().map(|inv| inv * atb) else {
        return f64::INFINITY;
    };
    pts.iter()
        .map(|&(e, f)| {
            let x = ((e - s) / scale).max(0.0);
            let r = c[0] * x + c[1] * x * x + c[2] * x * x * x - f;
            r * r
        })
        .sum()
}

/// The s in [lo, hi] of least `rss`: a grid of 60 steps, then golden-section refinement
/// around the best grid point.
fn search(lo: f64, hi: f64, rss: impl Fn(f64) -> f64) -> f64 {
    let n = 60;
    let grid: Vec<f64> = (0..=n)
        .map(|k| lo + (hi - lo) * k as f64 / n as f64)
        .collect();
    let k = (0..grid.len())
        .min_by(|&i, &j| rss(grid[i]).total_cmp(&rss(grid[j])))
        .unwrap_or(0);
    let h = (hi - lo) / n as f64;
    let (mut a, mut b) = (grid[k] - h, grid[k] + h);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..40 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if rss(c) < rss(d) {
            b = d;
        } else {
            a = c;
        }
    }
    0.5 * (a + b)
}

/// The start of a curve: every point up to the first above `frac` of the largest force, the
/// fraction widened from 40 % to 60, 80 and 100 % until 8 points at or above the floor lie in
/// it; `creep`: with the points under the floor.
fn window(elongation: &[f64], force: &[f64], fmax: f64, creep: bool) -> Vec<(f64, f64)> {
    window_from(elongation, force, fmax, creep, 0.4)
}

/// [`window`] from the fraction `first` of the largest force (widened from there as it is).
fn window_from(
    elongation: &[f64],
    force: &[f64],
    fmax: f64,
    creep: bool,
    first: f64,
) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for frac in [first, 0.4, 0.6, 0.8, 1.0]
        .into_iter()
        .filter(|&f| f >= first)
    {
        pts = elongation
            .iter()
            .zip(force)
            .take_while(|(_, &f)| f <= frac * fmax)
            .filter(|(_, &f)| creep || f >= TOE_FLOOR * fmax)
            .map(|(&e, &f)| (e, f))
            .collect();
        if pts.iter().filter(|p| p.1 >= TOE_FLOOR * fmax).count() >= 8 {
            break;
        }
    }
    pts
}

/// The toe of a curve (m; negative: a preload), or 0 when it has none (module doc).
pub fn detect_toe(elongation: &[f64], force: &[f64]) -> f64 {
    let fmax = force.iter().copied().fold(0.0, f64::max);
    if fmax <= 0.0 {
        return 0.0;
    }
    let s = hinge_toe(elongation, force, fmax);
    if s != 0.0 {
        s
    } else {
        flat_slack(elongation, force, fmax)
    }
}

/// The hinge rule (module doc).
fn hinge_toe(elongation: &[f64], force: &[f64], fmax: f64) -> f64 {
    // the creep of a slack strip (forces under 2 % of the largest) is left out: the zero is
    // where the steep region's curve, extended, reaches zero force
    let pts = window(elongation, force, fmax, false);
    if pts.len() < 6 {
        return 0.0;
    }
    let e_end = pts.last().map_or(0.0, |p| p.0);
    let rss0 = cubic_rss(&pts, 0.0);
    // s from a preload of a quarter of the region to three quarters of it (a slack strip's
    // zero lies ahead of the steep region)
    let s = search(-0.25 * e_end, 0.75 * e_end, |s| cubic_rss(&pts, s));
    let rss = cubic_rss(&pts, s);
    let total: f64 = pts.iter().map(|p| p.1 * p.1).sum();
    // a hinge has one parameter more than the cubic: it must fit ten times better, beyond
    // round-off; slack also needs measured evidence: two points or more below the new zero
    // (the creep), or a smooth stiffening curve sampled coarsely could pass for slack
    let creep = elongation.iter().filter(|&&e| e < s).count();
    let better = rss * 10.0 < rss0 && rss0 > 1e-5 * total;
    if better && (s < 0.0 || creep >= SLACK_POINTS) {
        s
    } else {
        0.0
    }
}

/// Least squares of a level c up to s and c plus a cubic in x = (e − s)/scale after it:
/// the residual sum of squares and (c, the cubic's coefficients of x, x², x³).
fn flat_hinge(pts: &[(f64, f64)], s: f64, scale: f64) -> (f64, [f64; 4]) {
    flat_rise(pts, s, scale, 1)
}

/// Least squares of a level c up to s and c plus x^p, x^(p+1), x^(p+2) after it (x = (e −
/// s)/scale): p = 1 a knee (a slope at s), p = 2 a smooth onset (none). The residual sum of
/// squares and the coefficients.
fn flat_rise(pts: &[(f64, f64)], s: f64, scale: f64, p: i32) -> (f64, [f64; 4]) {
    let row = |e: f64| {
        let x = ((e - s) / scale).max(0.0);
        let xp = x.powi(p);
        nalgebra::Vector4::new(1.0, xp, xp * x, xp * x * x)
    };
    let mut ata = nalgebra::Matrix4::<f64>::zeros();
    let mut atb = nalgebra::Vector4::<f64>::zeros();
    for &(e, f) in pts {
        let r = row(e);
        ata += r * r.transpose();
        atb += r * f;
    }
    let Some(c) = ata.try_inverse().map(|inv| inv * atb) else {
        return (f64::INFINITY, [0.0; 4]);
    };
    let rss = pts.iter().map(|&(e, f)| (row(e).dot(&c) - f).powi(2)).sum();
    (rss, [c[0], c[1], c[2], c[3]])
}

/// The flat-stretch rule (module doc): the slack s, or 0.
fn flat_slack(elongation: &[f64], force: &[f64], fmax: f64) -> f64 {
    for first in SLACK_WINDOWS {
        let s = flat_slack_in(&window_from(elongation, force, fmax, true, first), fmax);
        if s != 0.0 {
            return s;
        }
    }
    0.0
}

/// The flat-stretch rule on the points `pts` of one window.
fn flat_slack_in(pts: &[(f64, f64)], fmax: f64) -> f64 {
    let n = pts.len();
    let steep = pts.iter().filter(|p| p.1 >= TOE_FLOOR * fmax).count();
    if steep < 6 || n < 10 {
        return 0.0;
    }
    let e_end = pts[n - 1].0;
    // s leaves six points or more on the rise
    let s = search(0.0, pts[n - 6].0, |s| flat_hinge(pts, s, e_end).0);
    let (rss, c) = flat_hinge(pts, s, e_end);
    let rss0 = flat_hinge(pts, 0.0, e_end).0;
    let below: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.0 < s).collect();
    if below.len() < SLACK_POINTS || s <= 0.0 {
        return 0.0;
    }
    let var = rss / (n - 5) as f64;
    let significant = rss0 - rss >= SLACK_SIGNIFICANCE * var;
    let x_end = (e_end - s) / e_end;
    let mean_slope = c[1] + c[2] * x_end + c[3] * x_end * x_end;
    // a knee: the slope just after s is most of the rise's mean slope, or a level and a rise
    // from zero slope (a smooth onset, with its own s) fits worse by the significance margin
    let smooth_s = search(0.0, pts[n - 6].0, |s| flat_rise(pts, s, e_end, 2).0);
    let smooth_rss = flat_rise(pts, smooth_s, e_end, 2).0;
    let sharp = c[1] >= KNEE_SLOPE * mean_slope || smooth_rss - rss >= SLACK_SIGNIFICANCE * var;
    if significant && sharp && flat(&below[..below.len() - 1], var) {
        s
    } else {
        0.0
    }
}

/// Whether points show no trend: their least-squares slope within [`SLACK_TREND`] standard
/// errors of zero (fewer than two points: true). The standard error is at the points' own
/// noise (their residual variance about their line) where [`OWN_NOISE_POINTS`] or more lie
/// there, else at `var`: the window's variance mixes the rise's point noise, which grows with
/// the force, into the load cell's (`z0002-law`'s a75-2.csv: its slack's slope is 2.7 of its
/// own standard errors and more than 4 at the window's variance).
fn flat(pts: &[(f64, f64)], var: f64) -> bool {
    if pts.len() < 2 {
        return true;
    }
    let m = pts.len() as f64;
    let e_mean = pts.iter().map(|p| p.0).sum::<f64>() / m;
    let f_mean = pts.iter().map(|p| p.1).sum::<f64>() / m;
    let sxx: f64 = pts.iter().map(|p| (p.0 - e_mean).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - e_mean) * (p.1 - f_mean)).sum();
    if sxx <= 0.0 {
        return true;
    }
    let slope = sxy / sxx;
    let var = if pts.len() >= OWN_NOISE_POINTS {
        let r: f64 = pts
            .iter()
            .map(|p| (p.1 - f_mean - slope * (p.0 - e_mean)).powi(2))
            .sum();
        r / (m - 2.0)
    } else {
        var
    };
    slope * slope * sxx <= SLACK_TREND * SLACK_TREND * var
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(f: impl Fn(f64) -> f64, emax: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
        let e: Vec<f64> = (0..=n).map(|k| emax * k as f64 / n as f64).collect();
        let force = e.iter().map(|&x| f(x)).collect();
        (e, force)
    }

    /// Standard normal draws from a fixed seed (an LCG and Box–Muller).
    struct Noise(u64);

    impl Noise {
        fn uniform(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }

        fn normal(&mut self) -> f64 {
            let (a, b) = (self.uniform(), self.uniform());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        }
    }

    /// A strip of 75 mm under the paper's law: force ∝ E (μ₁ + μ₂ (1 + E²)^(α − 1)), E the
    /// strain, scaled to 50 N at `strain`.
    struct Law {
        alpha: f64,
        mu2: f64,
        strain: f64,
        /// more stiffening terms (μ, α), the linear one's μ lowered by theirs
        more: &'static [(f64, f64)],
    }

    impl Law {
        const GAUGE: f64 = 0.075;

        fn force(&self, e: f64) -> f64 {
            let sigma = |x: f64| {
                let strain = x / Self::GAUGE;
                let b = 1.0 + strain * strain;
                let mut eta = 1.0 - self.mu2 + self.mu2 * b.powf(self.alpha - 1.0);
                for &(mu, alpha) in self.more {
                    eta += mu * (b.powf(alpha - 1.0) - 1.0);
                }
                strain * eta
            };
            50.0 * sigma(e.max(0.0)) / sigma(self.strain * Self::GAUGE)
        }

        /// The lab's record: 120 points over the travel, `slack` of load-cell noise (sd
        /// `noise` of the largest force) ending in a knee or in a quadratic creep to 1 % of
        /// the largest force over its last 0.15 mm, the rise with 0.5 % of point noise on top,
        /// every force offset by `offset` of the largest.
        fn record(
            &self,
            slack: f64,
            creep: bool,
            noise: f64,
            offset: f64,
            seed: u64,
        ) -> (Vec<f64>, Vec<f64>) {
            self.record_of(120, slack, creep, noise, offset, seed)
        }

        /// [`Law::record`] with `points` points.
        fn record_of(
            &self,
            points: usize,
            slack: f64,
            creep: bool,
            noise: f64,
            offset: f64,
            seed: u64,
        ) -> (Vec<f64>, Vec<f64>) {
            let mut rng = Noise(seed);
            let travel = self.strain * Self::GAUGE + slack;
            let (mut e, mut f) = (Vec::new(), Vec::new());
            for i in 1..=points {
                let x = travel * i as f64 / points as f64;
                let rise = if x > slack {
                    self.force(x - slack) * (1.0 + 0.25 * noise * rng.normal())
                } else if creep {
                    let w = 0.15e-3f64.min(slack);
                    0.5 * ((x - slack + w) / w).max(0.0).powi(2)
                } else {
                    0.0
                };
                e.push(x);
                f.push(rise + 50.0 * (offset + noise * rng.normal()));
            }
            (e, f)
        }
    }

    /// The lab material's warp (α 150, 40 % stiffening term, to 5 %), a zoo fabric's weft
    /// (α 205, to 8 %) and a crimp-dominated yarn (α 300, 90 %, to 10 %: its first forces are
    /// lost in the noise).
    const LAWS: [Law; 3] = [
        Law {
            alpha: 150.0,
            mu2: 0.4,
            strain: 0.05,
            more: &[],
        },
        Law {
            alpha: 205.0,
            mu2: 0.34,
            strain: 0.08,
            more: &[],
        },
        Law {
            alpha: 300.0,
            mu2: 0.9,
            strain: 0.1,
            more: &[],
        },
    ];

    /// The lab zoo's `z0002-law` warp (degree 4: μ 0.21, 0.12, 0.33 at α 7.3, 109, 245), pulled
    /// to 11.6 %: its slope rises 10 times from the knee to 40 % of the largest force.
    const STEEP: Law = Law {
        alpha: 244.6,
        mu2: 0.3267,
        strain: 0.116,
        more: &[(0.2128, 7.32), (0.1189, 109.3)],
    };

    #[test]
    fn smooth_curves_through_the_origin_keep_their_zero() {
        // linear, stiffening (J-shaped, as crimp gives), and a law that softens
        for f in [
            &(|x: f64| 4000.0 * x) as &dyn Fn(f64) -> f64,
            &|x: f64| 2e3 * x + 4e6 * x * x + 3e9 * x * x * x,
            &|x: f64| 1e4 * x - 2e6 * x * x,
        ] {
            let (e, force) = curve(f, 3e-3, 40);
            assert_eq!(detect_toe(&e, &force), 0.0);
        }
    }

    #[test]
    fn slack_and_preload_are_found() {
        // 1 mm of slack before a stiffening curve; a preload of 0.3 mm equivalent
        let slack = 1e-3;
        let law = |x: f64| 8e3 * x + 2e6 * x * x;
        let (e, force) = curve(|x| if x > slack { law(x - slack) } else { 0.0 }, 6e-3, 60);
        let s = detect_toe(&e, &force);
        assert!((s - slack).abs() < 0.03e-3, "{s}");
        let (e, force) = curve(|x| law(x + 0.3e-3), 5e-3, 50);
        let s = detect_toe(&e, &force);
        assert!((s + 0.3e-3).abs() < 0.03e-3, "{s}");
    }

    /// Slack as a flat stretch of load-cell noise (sd 0.2 % of the largest force) before a
    /// stiffening rise, ending in a knee or a short creep, with and without a constant offset
    /// of the load cell: found to 0.075 mm (0.1 % of the gauge) at every length.
    #[test]
    fn noisy_flat_slack_is_found() {
        for (k, law) in LAWS[..2].iter().enumerate() {
            for slack in [0.2e-3, 0.5e-3, 1e-3, 2e-3] {
                for (creep, offset) in [(false, 0.0), (true, 0.0), (false, 0.003)] {
                    for seed in 1..=3 {
                        let (e, f) = law.record(slack, creep, 0.002, offset, seed + 10 * k as u64);
                        let s = detect_toe(&e, &f);
                        assert!(
                            (s - slack).abs() < 0.075e-3,
                            "law {k}, slack {slack}, creep {creep}, offset {offset}, seed {seed}: {s}"
                        );
                    }
                }
            }
        }
    }

    /// Stiffening curves without slack keep their zero, clean or noisy, offset or not: a
    /// convex onset that is the material's own is no toe.
    #[test]
    fn stiffening_curves_without_slack_keep_their_zero() {
        for (k, law) in LAWS.iter().enumerate() {
            for (noise, offset) in [(0.0, 0.0), (0.002, 0.0), (0.002, 0.003)] {
                for seed in 1..=3 {
                    let (e, f) = law.record(0.0, false, noise, offset, seed + 10 * k as u64);
                    let s = detect_toe(&e, &f);
                    assert_eq!(
                        s, 0.0,
                        "law {k}, noise {noise}, offset {offset}, seed {seed}"
                    );
                }
            }
        }
    }

    /// Slack before a law that stiffens tenfold within the first 40 % of its force (the zoo's
    /// `z0002-law` warp, 453 points a curve: 2 mm missed on all five repeats at 90°, 67.5° and
    /// 75° by the widest window alone), as a flat stretch of load-cell noise with or without an
    /// offset, on 450 points: found to 0.15 mm (0.2 % of the gauge; the rise's first 0.1 mm
    /// stays within the noise). Without slack the curve keeps its zero, or a toe over which
    /// the law's force stays within [`SLACK_TREND`] noise deviations (the trend the rule lets
    /// pass as flat).
    #[test]
    fn slack_before_a_steeply_stiffening_law_is_found() {
        for slack in [0.5e-3, 1e-3, 2e-3] {
            for offset in [0.0, 0.003] {
                for seed in 1..=3 {
                    let (e, f) = STEEP.record_of(450, slack, false, 0.002, offset, seed);
                    let s = detect_toe(&e, &f);
                    assert!(
                        (s - slack).abs() < 0.15e-3,
                        "slack {slack}, offset {offset}, seed {seed}: {s}"
                    );
                }
            }
        }
        for (noise, offset) in [(0.0, 0.0), (0.002, 0.0), (0.002, 0.003)] {
            for seed in 1..=3 {
                let (e, f) = STEEP.record_of(450, 0.0, false, noise, offset, seed);
                // where the law's first forces lie within the noise, that stretch may pass for
                // slack (0.53 mm, 3.2 deviations, on one record in six): never more than it
                let s = detect_toe(&e, &f);
                let within_noise = STEEP.force(s) < SLACK_TREND * 50.0 * noise;
                assert!(
                    s == 0.0 || (noise > 0.0 && within_noise),
                    "noise {noise}, offset {offset}, seed {seed}: {s}"
                );
            }
        }
    }
}
