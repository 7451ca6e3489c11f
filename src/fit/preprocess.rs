//! From lab curves to what the fit compares: toe compensation, the curves' roles and repeats,
//! and the strips the model solves (one per angle and geometry, shared by its repeats, solved
//! at a few elongation nodes and interpolated to every measured point).
//!
//! **Toe compensation.** Each curve's toe s (slack, or a preload when negative) is found by
//! [`detect_toe`] (the rules are in [`super::toe`]) unless the test gives `toe_mm`: the
//! curve's zero moves to s, points below it are dropped, the rest shifted, and the strip's rest
//! length taken as gauge + s (a slack strip is that much longer, a preloaded one that much
//! shorter).

use super::FitError;
use crate::dataset::{FabricDataset, Role, TensileTest};

/// How the toe of every curve is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ToeMode {
    /// Detect slack and preload and remove them (see the module doc).
    Auto,
    /// Keep every curve's zero as measured (a per-test `toe_mm` still applies).
    None,
}

/// Which repeats the fit uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RepeatMode {
    /// Every repeat, each curve weighted equally.
    All,
    /// The paper's choice: the repeat with the largest forces (warp, weft), the median one
    /// (other fitted angles).
    Largest,
}

/// A measured curve ready for the fit.
#[derive(Clone, Debug)]
pub struct Curve {
    /// index of the test in the dataset
    pub test: usize,
    pub angle_deg: f64,
    pub role: Role,
    /// 1-based among the tests at the same angle
    pub repeat: usize,
    pub used_in_fit: bool,
    /// elongation removed at the start, m (negative: a preload); `auto` when detected
    pub toe: f64,
    pub toe_auto: bool,
    /// (elongation after the toe, force) of every point the objective uses, m and N
    pub points: Vec<(f64, f64)>,
    /// points left out (in the toe, or with forces under 1e-3 of the largest)
    pub dropped: usize,
    /// index of its strip in [`Prepared::strips`]
    pub strip: usize,
}

/// A strip the model solves: one angle and geometry, shared by the curves measured on it.
#[derive(Clone, Debug)]
pub struct Strip {
    pub angle_deg: f64,
    pub width: f64,
    /// rest length: gauge length + toe
    pub length: f64,
    pub curves: Vec<usize>,
    /// elongations the model is solved at (increasing, the last the largest measured)
    pub nodes: Vec<f64>,
    /// the nodes are the measured elongations of every curve on the strip (no more of them
    /// than nodes asked for): the model forces at the points are solved, not interpolated
    pub at_points: bool,
}

/// The dataset's curves and strips.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub curves: Vec<Curve>,
    pub strips: Vec<Strip>,
    pub notes: Vec<String>,
    /// how a point's misfit enters every tensile stage's objective
    pub misfit: super::Misfit,
}

pub use super::toe::detect_toe;

/// Points of the local interpolant: six, a quintic (see [`nodes_for`] for why not a cubic).
pub const STENCIL: usize = 6;

/// Local quintic (Lagrange) interpolation weights of `x` over the nodes `0 ∪ nodes`: the
/// [`STENCIL`] points around the interval holding x (fewer where there are fewer). The model
/// force at x is Σ w_k F_k with F_0 = 0 at the origin. Returns (node index into `nodes`,
/// weight) pairs; the origin's weight is dropped (its force is zero).
pub fn interpolation_weights(nodes: &[f64], x: f64) -> Vec<(usize, f64)> {
    let mut all = vec![0.0];
    all.extend_from_slice(nodes);
    let n = all.len();
    if n == 1 {
        return Vec::new();
    }
    // the interval [all[i − 1], all[i]] holding x, and the stencil centred on it
    let i = all.partition_point(|&v| v <= x).clamp(1, n - 1);
    let m = STENCIL.min(n);
    let start = (i as isize - (STENCIL / 2) as isize).clamp(0, (n - m) as isize) as usize;
    let idx: Vec<usize> = (start..start + m).collect();
    let mut out = Vec::new();
    for &a in &idx {
        let mut w = 1.0;
        for &b in &idx {
            if a != b {
                w *= (x - all[b]) / (all[a] - all[b]);
            }
        }
        if a > 0 {
            out.push((a - 1, w));
        }
    }
    out
}

/// Node elongations for a strip whose largest measured elongation is `emax`: Chebyshev–Lobatto
/// spacing, emax (1 − cos(πk/n))/2, dense at both ends, where the curves bend most (the start
/// of a bias strip, and the strain cut-off at 95 % of the largest strain). On the strips of a
/// strongly stiffening degree-2 law, 12 such nodes keep a local cubic interpolant within
/// 0.15 % of solves at 120 elongations (10 evenly spread: 1.7 %; 14 of these: 0.08 %).
///
/// The interpolant is a local quintic ([`STENCIL`]): its error falls as h⁶ where a cubic's
/// falls as h⁴. On the five bundled fabrics (the end-of-fit check: solves halfway between the
/// nodes on 8 × 12), the largest error of the default fits and of the paper protocol's is
/// 0.080 % and 0.096 % with quintics on 9 nodes (no warning), against 0.111 % and 0.243 % on
/// 8 nodes (four fits warned, above 0.1 %) and 0.111 % and 0.153 % with cubics on 12 (canvas
/// and silk warned), so 9 is the default (`--nodes`): a quarter fewer equilibria than 12.
pub fn nodes_for(emax: f64, n: usize) -> Vec<f64> {
    (1..=n)
        .map(|k| emax * 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / n as f64).cos()))
        .collect()
}

fn max_force(t: &TensileTest) -> f64 {
    t.force.iter().cloned().fold(f64::MIN, f64::max)
}

/// The repeat number (from 1) of the next test at `angle`, given each angle met so far
/// (within 1e-9°) with its count of tests: one pass over the tests, not one per test.
fn repeat_number(seen: &mut Vec<(f64, usize)>, angle: f64) -> usize {
    match seen.iter_mut().find(|(a, _)| (*a - angle).abs() < 1e-9) {
        Some((_, n)) => {
            *n += 1;
            *n
        }
        None => {
            seen.push((angle, 1));
            1
        }
    }
}

/// Prepares every tensile curve: roles (`paper`: the paper's 0/45/90 split), repeats used,
/// toes, points, and the strips with `n_nodes` nodes each.
pub fn prepare(
    data: &FabricDataset,
    paper: bool,
    repeats: RepeatMode,
    toe: ToeMode,
    n_nodes: usize,
) -> Result<Prepared, FitError> {
    let mut notes = Vec::new();
    let mut curves = Vec::new();
    let mut seen: Vec<(f64, usize)> = Vec::new();
    for (i, t) in data.tensile.iter().enumerate() {
        let name = t.curve.display();
        if t.suspect_kn {
            return Err(FitError::Data(format!(
                "{name}: the forces look like kN (see the warning above); if they are, give `force_scale = 1000` for this test in the dataset (or another factor: 1/n for n strips pulled together); if they are right, `force_scale = 1` says so"
            )));
        }
        let fmax = max_force(t);
        if fmax.is_nan() || fmax <= 0.0 {
            return Err(FitError::Data(format!(
                "{name}: every force is zero or below: nothing to fit (is the force column right?)"
            )));
        }
        let (shift, auto) = match (t.toe, toe) {
            (Some(s), _) => (s, false),
            (None, ToeMode::Auto) => (detect_toe(&t.elongation, &t.force), true),
            (None, ToeMode::None) => (0.0, false),
        };
        let mut points = Vec::new();
        let mut dropped = 0;
        for (&e, &f) in t.elongation.iter().zip(&t.force) {
            let x = e - shift;
            if x > 0.0 && f > 1e-3 * fmax {
                points.push((x, f));
            } else {
                dropped += 1;
            }
        }
        if points.len() < 2 {
            return Err(FitError::Data(format!(
                "{name}: fewer than two points with force after the toe ({:.3} mm removed): nothing to fit",
                shift * 1e3
            )));
        }
        if shift != 0.0 {
            let what = if shift > 0.0 { "slack" } else { "preload" };
            notes.push(format!(
                "{name}: toe {:.3} mm removed ({what}, {}){}",
                shift * 1e3,
                if auto { "detected" } else { "toe_mm" },
                if shift.abs() > 0.01 * t.gauge_length {
                    format!(
                        "; warning: above 1 % of the {:.0} mm gauge length",
                        t.gauge_length * 1e3
                    )
                } else {
                    String::new()
                }
            ));
        }
        let repeat = repeat_number(&mut seen, t.angle_deg);
        curves.push(Curve {
            test: i,
            angle_deg: t.angle_deg,
            role: t.role(paper),
            repeat,
            used_in_fit: false,
            toe: shift,
            toe_auto: auto,
            points,
            dropped,
            strip: 0,
        });
    }
    choose_repeats(data, &mut curves, repeats, &mut notes);
    let strips = group_strips(data, &mut curves, n_nodes);
    Ok(Prepared {
        curves,
        strips,
        notes,
        misfit: Default::default(),
    })
}

/// Marks the curves the fit uses.
fn choose_repeats(
    data: &FabricDataset,
    curves: &mut [Curve],
    mode: RepeatMode,
    notes: &mut Vec<String>,
) {
    let mut angles: Vec<f64> = curves.iter().map(|c| c.angle_deg).collect();
    angles.sort_by(f64::total_cmp);
    angles.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    for angle in angles {
        let mut at: Vec<usize> = (0..curves.len())
            .filter(|&k| (curves[k].angle_deg - angle).abs() < 1e-9 && curves[k].role == Role::Fit)
            .collect();
        if at.is_empty() {
            continue;
        }
        if mode == RepeatMode::All || at.len() == 1 {
            at.iter().for_each(|&k| curves[k].used_in_fit = true);
            continue;
        }
        at.sort_by(|&a, &b| {
            max_force(&data.tensile[curves[a].test])
                .total_cmp(&max_force(&data.tensile[curves[b].test]))
        });
        let axis = (angle - 90.0).abs() < 1e-9 || angle.abs() < 1e-9;
        let k = if axis {
            at[at.len() - 1]
        } else {
            at[at.len() / 2]
        };
        curves[k].used_in_fit = true;
        notes.push(format!(
            "{angle}°: fitted repeat {} of {} ({}; --repeat largest)",
            data.tensile[curves[k].test].curve.display(),
            at.len(),
            if axis {
                "the largest forces"
            } else {
                "the median largest force"
            }
        ));
    }
}

/// Groups curves measured on the same strip (angle, width, rest length) and gives each
/// strip its nodes.
fn group_strips(data: &FabricDataset, curves: &mut [Curve], n_nodes: usize) -> Vec<Strip> {
    let mut strips: Vec<Strip> = Vec::new();
    for (k, c) in curves.iter_mut().enumerate() {
        let t = &data.tensile[c.test];
        let length = t.gauge_length + c.toe;
        let same = |s: &Strip| {
            (s.angle_deg - c.angle_deg).abs() < 1e-9
                && (s.width - t.width).abs() <= 1e-12 * t.width
                && (s.length - length).abs() <= 1e-12 * length
        };
        let i = match strips.iter().position(same) {
            Some(i) => i,
            None => {
                strips.push(Strip {
                    angle_deg: c.angle_deg,
                    width: t.width,
                    length,
                    curves: Vec::new(),
                    nodes: Vec::new(),
                    at_points: false,
                });
                strips.len() - 1
            }
        };
        strips[i].curves.push(k);
        c.strip = i;
    }
    for s in &mut strips {
        let mut points: Vec<f64> = s
            .curves
            .iter()
            .flat_map(|&k| curves[k].points.iter().map(|p| p.0))
            .collect();
        points.sort_by(f64::total_cmp);
        points.dedup();
        if points.len() <= n_nodes {
            s.nodes = points;
            s.at_points = true;
        } else {
            // a curve's points increase, so the largest is some curve's last
            s.nodes = nodes_for(points.last().copied().unwrap_or(0.0), n_nodes);
        }
    }
    strips
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip with no more distinct measured elongations (over all its curves) than nodes is
    /// solved at them; one with more gets the Chebyshev–Lobatto nodes, as do repeats whose
    /// grids differ enough to make more than the node count together.
    #[test]
    fn strips_with_few_points_are_solved_at_them() {
        use crate::dataset::{FabricDataset, TensileTest};
        let test = |angle: f64, elongation: Vec<f64>| TensileTest {
            angle_deg: angle,
            width: 0.05,
            gauge_length: 0.075,
            curve: format!("{angle}.csv").into(),
            force: elongation.iter().map(|e| 1e4 * e).collect(),
            elongation,
            role: None,
            toe: Some(0.0),
            force_scale: 1.0,
            columns: None,
            suspect_kn: false,
        };
        let grid = |n: usize, offset: f64| -> Vec<f64> {
            (1..=n).map(|k| 1e-3 * (k as f64 + offset)).collect()
        };
        let data = FabricDataset {
            name: "few".into(),
            path: "few.toml".into(),
            areal_density: Some(0.1),
            thickness: 2e-4,
            // two repeats on one grid of 5, one curve of 20, two repeats on grids of 7 apart
            tensile: vec![
                test(90.0, grid(5, 0.0)),
                test(90.0, grid(5, 0.0)),
                test(45.0, grid(20, 0.0)),
                test(0.0, grid(7, 0.0)),
                test(0.0, grid(7, 0.5)),
            ],
            bend: Vec::new(),
            shapes: Vec::new(),
            known: Default::default(),
            notes: Vec::new(),
        };
        let prep = prepare(&data, false, RepeatMode::All, ToeMode::None, 12).unwrap();
        let strip = |angle: f64| prep.strips.iter().find(|s| s.angle_deg == angle).unwrap();
        assert!(strip(90.0).at_points);
        assert_eq!(strip(90.0).nodes, grid(5, 0.0));
        // every measured point then has its own node's force, weight 1
        for &e in &grid(5, 0.0) {
            let w = interpolation_weights(&strip(90.0).nodes, e);
            let own: Vec<_> = w.iter().filter(|(_, w)| *w != 0.0).collect();
            assert_eq!(own.len(), 1, "{e}: {w:?}");
            assert_eq!(own[0].1, 1.0);
            assert_eq!(strip(90.0).nodes[own[0].0], e);
        }
        for angle in [45.0, 0.0] {
            assert!(!strip(angle).at_points, "{angle}");
            assert_eq!(strip(angle).nodes.len(), 12, "{angle}");
        }
        assert_eq!(strip(45.0).nodes, nodes_for(20e-3, 12));
        assert_eq!(strip(0.0).nodes, nodes_for(7.5e-3, 12));
    }

    #[test]
    fn interpolation_is_exact_for_quintics_and_uses_the_origin() {
        let nodes = nodes_for(2.0, 7);
        let f =
            |x: f64| 3.0 * x + 0.5 * x * x - 0.25 * x.powi(3) + 0.1 * x.powi(4) - 0.02 * x.powi(5);
        for x in [0.01, 0.3, 0.77, 1.4, 2.0] {
            let v: f64 = interpolation_weights(&nodes, x)
                .iter()
                .map(|&(k, w)| w * f(nodes[k]))
                .sum();
            assert!((v - f(x)).abs() < 1e-12, "{x}: {v} vs {}", f(x));
        }
    }
}
