//! Mesh-refinement studies: run one scene over a ladder of meshes, each twice as fine as the
//! last, and estimate the converged value, the error of each level and the observed order.
//!
//! With refinement ratio 2 and three consecutive values q₀, q₁, q₂ (coarse to fine), the
//! observed order is p = log₂(|q₀ − q₁| / |q₁ − q₂|) and Richardson's estimate of the limit is
//! q∞ = q₂ + (q₂ − q₁)/(2ᵖ − 1). Each level's estimated error is |q − q∞| / |q∞|, using the
//! estimate from the finest triple; the order is reported for each triple, at its middle level.

use std::time::Instant;

/// One rung of the ladder.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub mesh: (usize, usize),
    pub dofs: usize,
    pub seconds: f64,
    pub qoi: f64,
    /// q(next finer) − q(this)
    pub diff_to_next: Option<f64>,
    /// |q − q∞| / |q∞| with the finest Richardson estimate
    pub est_error: Option<f64>,
    /// observed order of the triple centred here
    pub order: Option<f64>,
}

impl Level {
    /// A solved level, before the study's differences, orders and estimates.
    pub fn solved(mesh: (usize, usize), dofs: usize, seconds: f64, qoi: f64) -> Self {
        Level {
            mesh,
            dofs,
            seconds,
            qoi,
            diff_to_next: None,
            est_error: None,
            order: None,
        }
    }
}

/// A whole study.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    pub levels: Vec<Level>,
    /// Richardson estimate of the converged value (needs three levels).
    pub extrapolated: Option<f64>,
}

/// The default ladder: (nx, ny) = (4, round(4 · aspect)) · 2^k for k = 0..levels, `aspect`
/// being length / width (4 × 6, 8 × 12, … for a 50 × 75 mm strip). Every rung is exactly twice
/// as fine as the last, as Richardson extrapolation assumes.
/// `levels` is at most [`MAX_LEVELS`] (the sizes would overflow far beyond it).
pub fn default_ladder(aspect: f64, levels: usize) -> Vec<(usize, usize)> {
    let ny0 = ((4.0 * aspect).round() as usize).max(1);
    (0..levels.min(MAX_LEVELS))
        .map(|k| (4usize << k, ny0.saturating_mul(1 << k)))
        .collect()
}

/// Most levels of a default ladder: 4 × 6 doubled ten times is 2048 × 3072, 6 million faces.
pub const MAX_LEVELS: usize = 10;

/// Parses "4x6,8x12,16x24".
pub fn parse_ladder(s: &str) -> Result<Vec<(usize, usize)>, String> {
    s.split(',')
        .map(|m| {
            let bad =
                || format!("mesh must look like 8x12 (faces across x faces along), got '{m}'");
            let (a, b) = m.trim().split_once(['x', 'X']).ok_or_else(bad)?;
            let (nx, ny) = (
                a.trim().parse::<usize>().map_err(|_| bad())?,
                b.trim().parse::<usize>().map_err(|_| bad())?,
            );
            if nx == 0 || ny == 0 {
                return Err(bad());
            }
            Ok((nx, ny))
        })
        .collect()
}

/// Checks a ladder before any level runs: each mesh within the face limit
/// ([`crate::limits`]) and finer than the previous one; with `doubling`, exactly twice as fine in
/// both directions, as the Richardson estimate and the observed order assume.
pub fn check_ladder(ladder: &[(usize, usize)], doubling: bool) -> Result<(), String> {
    for (k, &(nx, ny)) in ladder.iter().enumerate() {
        crate::limits::check_mesh(&format!("mesh {nx}x{ny}"), nx, ny)?;
        if k == 0 {
            continue;
        }
        let (px, py) = ladder[k - 1];
        let finer = if doubling {
            nx == 2 * px && ny == 2 * py
        } else {
            nx >= px && ny >= py && nx.saturating_mul(ny) > px * py
        };
        if !finer {
            return Err(format!(
                "mesh {nx}x{ny} after {px}x{py}: each mesh must be {} the one before",
                if doubling {
                    "twice as fine in both directions as"
                } else {
                    "finer than"
                }
            ));
        }
    }
    Ok(())
}

/// Runs `scene(mesh) -> (qoi, dofs)` on each mesh (calling `progress` after each) and analyses
/// the results.
pub fn study<E>(
    ladder: &[(usize, usize)],
    mut scene: impl FnMut((usize, usize)) -> Result<(f64, usize), E>,
    mut progress: impl FnMut(&Level),
) -> Result<Study, E> {
    let mut levels = Vec::with_capacity(ladder.len());
    for &mesh in ladder {
        let t0 = Instant::now();
        let (qoi, dofs) = scene(mesh)?;
        let level = Level::solved(mesh, dofs, t0.elapsed().as_secs_f64(), qoi);
        progress(&level);
        levels.push(level);
    }
    Ok(analyse(levels))
}

/// Differences, orders and the Richardson estimate of solved levels.
pub fn analyse(mut levels: Vec<Level>) -> Study {
    let n = levels.len();
    for i in 0..n.saturating_sub(1) {
        levels[i].diff_to_next = Some(levels[i + 1].qoi - levels[i].qoi);
    }
    let mut extrapolated = None;
    for i in 1..n.saturating_sub(1) {
        let (q0, q1, q2) = (levels[i - 1].qoi, levels[i].qoi, levels[i + 1].qoi);
        let (d0, d1) = ((q0 - q1).abs(), (q1 - q2).abs());
        if d0 > 0.0 && d1 > 0.0 {
            let p = (d0 / d1).log2();
            levels[i].order = Some(p);
            if i == n - 2 && p > 0.0 {
                extrapolated = Some(q2 + (q2 - q1) / (p.exp2() - 1.0));
            }
        } else if d1 == 0.0 && i == n - 2 {
            extrapolated = Some(q2);
        }
    }
    with_limit(levels, extrapolated)
}

/// As [`analyse`], but the limit comes only from a monotone, contracting finest triple
/// ([`monotone_limit`]): the stricter estimate, for a mesh chosen without a person to read
/// the table (the synthetic cantilevers' overhang search).
pub fn analyse_monotone(levels: Vec<Level>) -> Study {
    let n = levels.len();
    let limit = if n >= 3 {
        monotone_limit(levels[n - 3].qoi, levels[n - 2].qoi, levels[n - 1].qoi)
    } else {
        None
    };
    let levels = analyse(levels).levels;
    with_limit(levels, limit)
}

/// The study of `levels` with the limit `extrapolated`: each level's estimated relative error.
fn with_limit(mut levels: Vec<Level>, extrapolated: Option<f64>) -> Study {
    for l in &mut levels {
        l.est_error = extrapolated.map(|q| ((l.qoi - q) / q).abs());
    }
    Study {
        levels,
        extrapolated,
    }
}

/// Differences below this fraction of a point's value are round-off: three levels that agree
/// to it are converged (a homogeneous strip gives the same force on every mesh).
pub const ROUND_OFF: f64 = 1e-9;

/// Points whose converged value is below this fraction of the curve's largest are left out
/// of a curve's error (a relative error of a force near zero says nothing of the curve).
pub const CURVE_FLOOR: f64 = 0.05;

/// Richardson's limit of three values, coarse to fine, each level twice as fine as the last:
/// the finest where the three agree to [`ROUND_OFF`] (or the last two exactly), else only from
/// a monotone, contracting triple (`None` for an oscillating or diverging one, whose estimate
/// would be optimistic or meaningless).
pub fn monotone_limit(q0: f64, q1: f64, q2: f64) -> Option<f64> {
    let (d0, d1) = (q1 - q0, q2 - q1);
    let scale = q0.abs().max(q1.abs()).max(q2.abs());
    if d0.abs().max(d1.abs()) <= ROUND_OFF * scale || d1 == 0.0 {
        Some(q2)
    } else if d0 * d1 > 0.0 && d1.abs() < d0.abs() {
        let p = (d0 / d1).log2();
        Some(q2 + d1 / (p.exp2() - 1.0))
    } else {
        None
    }
}

/// Richardson's estimate of a curve's relative discretisation error from two meshes at a known
/// order `order` (the finer `fine`, the other with half its faces each way, `rough`): the mean
/// |(fine − rough)/fine| over the points where it is finite, divided by 2ᵖ − 1. Two levels
/// suffice where the order is known (the fitter's strips: the cage's measured order); with an
/// unknown order, [`curve_errors`] estimates it from three.
pub fn known_order_error(fine: &[f64], rough: &[f64], order: f64) -> f64 {
    let d: Vec<f64> = fine
        .iter()
        .zip(rough)
        .map(|(a, b)| (a - b) / a)
        .filter(|v| v.is_finite())
        .collect();
    let mean = d.iter().map(|v| v.abs()).sum::<f64>() / d.len().max(1) as f64;
    mean / (2f64.powf(order) - 1.0)
}

/// Estimated relative error of each of several curves of the same points (coarse to fine,
/// each level twice as fine as the last): at each point the limit q∞ is extrapolated from
/// the three finest levels as in [`analyse`], but only from a monotone triple (an
/// oscillating one would make the estimate optimistic), or taken as the finest value where
/// the three agree to [`ROUND_OFF`]. A level's error is the largest |q − q∞| / |q∞| over the
/// points at or above [`CURVE_FLOOR`] of the largest |q∞|; `None` for every level when some
/// such point has no estimate, or when there are fewer than three levels.
pub fn curve_errors(curves: &[Vec<f64>]) -> Vec<Option<f64>> {
    let n = curves.len();
    let none = vec![None; n];
    if n < 3 || curves.iter().any(|c| c.len() != curves[0].len()) {
        return none;
    }
    let (c0, c1, c2) = (&curves[n - 3], &curves[n - 2], &curves[n - 1]);
    let limit: Vec<Option<f64>> = c0
        .iter()
        .zip(c1)
        .zip(c2)
        .map(|((&q0, &q1), &q2)| monotone_limit(q0, q1, q2))
        .collect();
    let top = limit.iter().flatten().fold(0.0f64, |m, q| m.max(q.abs()));
    let mut errors = vec![Some(0.0f64); n];
    for (k, q) in limit.iter().enumerate() {
        let counts = match q {
            Some(q) => q.abs() >= CURVE_FLOOR * top && *q != 0.0,
            None => c2[k].abs() >= CURVE_FLOOR * top,
        };
        if !counts {
            continue;
        }
        let Some(q) = q else { return none };
        for (e, c) in errors.iter_mut().zip(curves) {
            *e = e.map(|e| e.max(((c[k] - q) / q).abs()));
        }
    }
    if top == 0.0 {
        return none;
    }
    errors
}

/// How a level's error is measured against a tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErrorMeasure {
    /// |q − q∞| / |q∞| ([`Level::est_error`])
    Relative,
    /// |q − q∞|, in the quantity's own unit (a drape angle's degrees)
    Absolute,
}

/// The mesh a ladder keeps for a tolerance: the coarsest level whose Richardson estimate meets
/// it, else the finest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chosen {
    /// level `index` is the coarsest that meets the tolerance, with this estimated error
    Met { index: usize, error: f64 },
    /// no level meets it: the finest, with its estimated error
    NotMet { error: f64 },
    /// the ladder does not converge monotonically, so there is no estimate: the finest
    NoEstimate,
}

impl Chosen {
    /// The index of the kept level in a ladder of `levels` levels.
    pub fn index(&self, levels: usize) -> usize {
        match *self {
            Chosen::Met { index, .. } => index,
            _ => levels.saturating_sub(1),
        }
    }

    /// The kept level's estimated error, if there is an estimate.
    pub fn error(&self) -> Option<f64> {
        match *self {
            Chosen::Met { error, .. } | Chosen::NotMet { error } => Some(error),
            Chosen::NoEstimate => None,
        }
    }
}

impl Study {
    /// Each level's estimated error in `measure` (`None` without an extrapolated value).
    pub fn errors(&self, measure: ErrorMeasure) -> Vec<Option<f64>> {
        self.levels
            .iter()
            .map(|l| match measure {
                ErrorMeasure::Relative => l.est_error,
                ErrorMeasure::Absolute => self.extrapolated.map(|q| (l.qoi - q).abs()),
            })
            .collect()
    }

    /// The coarsest level whose estimated error is below `tol`, else the finest: the one rule
    /// by which every automatic mesh of a scene is kept.
    pub fn choose(&self, tol: f64, measure: ErrorMeasure) -> Chosen {
        let errors = self.errors(measure);
        if let Some(index) = errors.iter().position(|e| e.is_some_and(|e| e < tol)) {
            let error = errors[index].unwrap_or(0.0);
            return Chosen::Met { index, error };
        }
        match errors.last().copied().flatten() {
            Some(error) => Chosen::NotMet { error },
            None => Chosen::NoEstimate,
        }
    }

    /// Whitespace-aligned table with a header row.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<10} {:>8} {:>9} {:>22} {:>12} {:>22} {:>10} {:>7}\n",
            "mesh", "dofs", "seconds", "qoi", "diff_next", "richardson", "est_error", "order"
        );
        let opt = |v: Option<f64>, prec: usize| match v {
            Some(x) => format!("{x:.prec$e}"),
            None => "-".into(),
        };
        for l in &self.levels {
            s.push_str(&format!(
                "{:<10} {:>8} {:>9.3} {:>22.15e} {:>12} {:>22} {:>10} {:>7}\n",
                format!("{}x{}", l.mesh.0, l.mesh.1),
                l.dofs,
                l.seconds,
                l.qoi,
                opt(l.diff_to_next, 3),
                opt(self.extrapolated, 15),
                opt(l.est_error, 2),
                l.order
                    .map(|p| format!("{p:.2}"))
                    .unwrap_or_else(|| "-".into())
            ));
        }
        s
    }

    /// CSV with header `mesh,nx,ny,dofs,seconds,qoi,diff_next,richardson,est_error,order`.
    pub fn csv(&self) -> String {
        let mut s =
            String::from("mesh,nx,ny,dofs,seconds,qoi,diff_next,richardson,est_error,order\n");
        let opt = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
        for l in &self.levels {
            s.push_str(&format!(
                "{}x{},{},{},{},{},{:e},{},{},{},{}\n",
                l.mesh.0,
                l.mesh.1,
                l.mesh.0,
                l.mesh.1,
                l.dofs,
                l.seconds,
                l.qoi,
                opt(l.diff_to_next),
                opt(self.extrapolated),
                opt(l.est_error),
                opt(l.order)
            ));
        }
        s
    }

    /// An SVG chart: estimated error against DOFs (left) and against wall time (right), both
    /// log–log. Errors below 1e-16 (exact on every mesh) are drawn at 1e-16.
    pub fn svg(&self, title: &str) -> Result<String, String> {
        use plotters::prelude::*;
        let pts: Vec<(f64, f64, f64)> = self
            .levels
            .iter()
            .filter_map(|l| {
                l.est_error
                    .map(|e| (l.dofs as f64, l.seconds.max(1e-6), e.max(1e-16)))
            })
            .collect();
        if pts.len() < 2 {
            return Err("need at least two levels with an error estimate to plot".into());
        }
        let mut buf = String::new();
        {
            let root = SVGBackend::with_string(&mut buf, (960, 420)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| e.to_string())?;
            let root = root
                .titled(title, ("sans-serif", 18))
                .map_err(|e| e.to_string())?;
            let (left, right) = root.split_horizontally(480);
            let range = |v: &dyn Fn(&(f64, f64, f64)) -> f64| {
                let lo = pts.iter().map(v).fold(f64::MAX, f64::min);
                let hi = pts.iter().map(v).fold(f64::MIN, f64::max);
                (lo / 2.0)..(hi * 2.0)
            };
            let err = range(&|p| p.2);
            for (area, xs, label) in [
                (&left, range(&|p| p.0), "degrees of freedom"),
                (&right, range(&|p| p.1), "wall time (s)"),
            ] {
                let mut chart = ChartBuilder::on(area)
                    .margin(12)
                    .x_label_area_size(36)
                    .y_label_area_size(60)
                    .build_cartesian_2d(xs.log_scale(), err.clone().log_scale())
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc(label)
                    .y_desc("estimated relative error")
                    .draw()
                    .map_err(|e| e.to_string())?;
                let series: Vec<(f64, f64)> = pts
                    .iter()
                    .map(|p| (if label.starts_with("deg") { p.0 } else { p.1 }, p.2))
                    .collect();
                chart
                    .draw_series(LineSeries::new(series.clone(), &BLUE))
                    .map_err(|e| e.to_string())?;
                chart
                    .draw_series(series.iter().map(|&p| Circle::new(p, 4, BLUE.filled())))
                    .map_err(|e| e.to_string())?;
            }
            root.present().map_err(|e| e.to_string())?;
        }
        Ok(buf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_errors_extrapolate_each_point_and_refuse_oscillation() {
        // q_k(x) = x (1 + 0.4 h²), h = 1/2^k: order 2 at every point, limit x
        let xs = [0.0, 0.01, 1.0, 2.0];
        let curve = |k: i32| -> Vec<f64> {
            let h = 0.5f64.powi(k);
            xs.iter().map(|x| x * (1.0 + 0.4 * h * h)).collect()
        };
        let e = curve_errors(&[curve(0), curve(1), curve(2), curve(3)]);
        for (k, e) in e.iter().enumerate() {
            let want = 0.4 * 0.25f64.powi(k as i32);
            assert!(
                (e.unwrap() - want).abs() < 1e-12 * want.max(1.0),
                "{k}: {e:?}"
            );
        }
        // a homogeneous strip: the same value to round-off on every mesh is converged
        let flat = vec![
            vec![1.0, 2.0],
            vec![1.0, 2.0 + 1e-12],
            vec![1.0 + 1e-13, 2.0],
        ];
        assert!(curve_errors(&flat).iter().all(|e| e.unwrap() < 1e-11));
        // an oscillating point above the floor gives no estimate at all
        let mut osc = vec![curve(0), curve(1), curve(2)];
        osc[1][3] = 1.9;
        assert!(curve_errors(&osc).iter().all(|e| e.is_none()));
        // below the floor it is left out
        let mut low = vec![curve(0), curve(1), curve(2)];
        low[1][1] = 0.02;
        assert!(curve_errors(&low).iter().all(|e| e.is_some()));
        assert!(curve_errors(&[curve(0), curve(1)])
            .iter()
            .all(|e| e.is_none()));
    }

    #[test]
    fn recovers_order_and_limit_of_a_known_sequence() {
        // q(h) = 2 + 3 h² with h = 1/2^k: order 2, limit 2
        let ladder = default_ladder(1.5, 4);
        assert_eq!(ladder, vec![(4, 6), (8, 12), (16, 24), (32, 48)]);
        let s = study(
            &ladder,
            |(nx, _)| Ok::<_, ()>((2.0 + 3.0 / (nx as f64 * nx as f64), nx)),
            |_| {},
        )
        .unwrap();
        assert!((s.extrapolated.unwrap() - 2.0).abs() < 1e-12);
        for l in &s.levels[1..3] {
            assert!((l.order.unwrap() - 2.0).abs() < 1e-9);
        }
        let mesh = |tol: f64| match s.choose(tol, ErrorMeasure::Relative) {
            Chosen::Met { index, .. } => Some(s.levels[index].mesh),
            _ => None,
        };
        assert_eq!(mesh(2e-3), Some((32, 48)));
        assert_eq!(mesh(1e-3), None);
        assert_eq!(mesh(1e-2), Some((16, 24)));
        assert!(s.table().starts_with("mesh"));
        assert!(s.csv().starts_with("mesh,nx,ny,dofs,seconds,qoi"));
        assert!(s.svg("test").unwrap().contains("<svg"));
        assert_eq!(parse_ladder("4x6, 8X12").unwrap(), vec![(4, 6), (8, 12)]);
        assert!(parse_ladder("4x0").is_err());
    }

    fn levels(qois: &[f64]) -> Vec<Level> {
        qois.iter()
            .enumerate()
            .map(|(k, &qoi)| Level::solved((4 << k, 6 << k), 0, 0.0, qoi))
            .collect()
    }

    #[test]
    fn choose_keeps_the_coarsest_level_that_meets_the_tolerance_else_the_finest() {
        // 10, 11, 11.5: order 1, limit 12, absolute errors 2, 1 and 0.5
        let s = analyse(levels(&[10.0, 11.0, 11.5]));
        assert_eq!(s.extrapolated, Some(12.0));
        let met = s.choose(1.5, ErrorMeasure::Absolute);
        assert_eq!(
            met,
            Chosen::Met {
                index: 1,
                error: 1.0
            }
        );
        assert_eq!(met.index(3), 1);
        let not_met = s.choose(0.4, ErrorMeasure::Absolute);
        assert_eq!(not_met, Chosen::NotMet { error: 0.5 });
        assert_eq!(not_met.index(3), 2);
        // relative: 1/12 on the middle level
        let rel = s.choose(0.1, ErrorMeasure::Relative);
        assert_eq!(rel.index(3), 1);
        assert!((rel.error().unwrap() - 1.0 / 12.0).abs() < 1e-15);
        // no change between the coarse two: no order, no estimate
        let flat = analyse(levels(&[10.0, 10.0, 11.0]));
        assert_eq!(
            flat.choose(100.0, ErrorMeasure::Absolute),
            Chosen::NoEstimate
        );
        assert_eq!(flat.choose(100.0, ErrorMeasure::Relative).index(3), 2);
    }

    #[test]
    fn the_monotone_study_gives_no_estimate_for_an_oscillating_ladder() {
        // monotone and contracting: the same limit and choice as the plain study
        let plain = analyse(levels(&[10.0, 11.0, 11.5]));
        let strict = analyse_monotone(levels(&[10.0, 11.0, 11.5]));
        assert_eq!(strict, plain);
        // 10, 11, 10.5 contracts but oscillates: the plain study extrapolates, the strict
        // one does not
        let plain = analyse(levels(&[10.0, 11.0, 10.5]));
        assert!(plain.extrapolated.is_some());
        let strict = analyse_monotone(levels(&[10.0, 11.0, 10.5]));
        assert_eq!(strict.extrapolated, None);
        assert!(strict.levels.iter().all(|l| l.est_error.is_none()));
        assert_eq!(
            strict.choose(100.0, ErrorMeasure::Absolute),
            Chosen::NoEstimate
        );
        // the orders and differences are the plain study's
        assert_eq!(strict.levels[1].order, plain.levels[1].order);
        assert_eq!(strict.levels[0].diff_to_next, Some(1.0));
    }
}
