//! The stages of a triangle-model fit: which targets each stage sees, each stage's fit, the
//! repeated passes over them and the joint bending fit, each kept only where the fitted lab
//! tests gain as a whole.

use super::minimise::{cost, levenberg_marquardt, stage};
use super::{near, tie_diagonal, Target, TriFitOptions};
use crate::tri::params::{TriKind, TriMaterial};

/// The targets each stage fits, by index.
pub(super) struct StageSets {
    pub warp: Vec<usize>,
    pub weft: Vec<usize>,
    /// the fitted off-axis strips
    pub off: Vec<usize>,
    pub bend_warp: Vec<usize>,
    pub bend_weft: Vec<usize>,
    /// each bending stage's set: its cantilevers, and for the springs the strips along the
    /// same yarn
    pub bend_warp_set: Vec<usize>,
    pub bend_weft_set: Vec<usize>,
    /// the fitted lab tests (strips and cantilevers), whose whole cost judges a pass
    pub lab: Vec<usize>,
}

impl StageSets {
    pub(super) fn new(targets: &[Target], kind: TriKind) -> Self {
        let select = |pred: &dyn Fn(&Target) -> bool| -> Vec<usize> {
            (0..targets.len()).filter(|&i| pred(&targets[i])).collect()
        };
        let is_strip_at =
            |a: f64| move |t: &Target| matches!(t, Target::Strip { .. }) && near(t.angle_deg(), a);
        let warp = select(&is_strip_at(90.0));
        let weft = select(&is_strip_at(0.0));
        let off: Vec<usize> = select(&|t: &Target| {
            matches!(t, Target::Strip { fitted: true, .. })
                && !near(t.angle_deg(), 0.0)
                && !near(t.angle_deg(), 90.0)
        });
        let bend_warp =
            select(&|t: &Target| matches!(t, Target::Bend { .. }) && near(t.angle_deg(), 90.0));
        let bend_weft =
            select(&|t: &Target| matches!(t, Target::Bend { .. }) && near(t.angle_deg(), 0.0));
        // the springs' ring-2 bending springs also carry stretch: their bending stages see the
        // strips along the same yarn too, or a cantilever's bending springs stiffen until the
        // strip is several times too stiff (on a shell's cotton, 600 % on the weft)
        let with = |a: &Vec<usize>, b: &Vec<usize>| -> Vec<usize> {
            if kind == TriKind::Springs && !a.is_empty() {
                a.iter().chain(b).copied().collect()
            } else {
                a.clone()
            }
        };
        let (bend_warp_set, bend_weft_set) = (with(&bend_warp, &warp), with(&bend_weft, &weft));
        let lab: Vec<usize> = select(&|t: &Target| match t {
            Target::Strip { fitted, .. } => *fitted,
            Target::Bend { .. } => true,
            Target::Shape(_) => false,
        });
        StageSets {
            warp,
            weft,
            off,
            bend_warp,
            bend_weft,
            bend_warp_set,
            bend_weft_set,
            lab,
        }
    }

    /// The stages in order: name, curve fitted and the targets it sees (no shear stage for
    /// the springs).
    pub(super) fn stages(&self, kind: TriKind) -> Vec<(&'static str, usize, &[usize])> {
        let mut stages: Vec<(&'static str, usize, &[usize])> = vec![
            ("warp stretch", 0, &self.warp),
            ("weft stretch", 1, &self.weft),
            ("shear", 2, &self.off),
            ("warp bending", 3, &self.bend_warp_set),
            ("weft bending", 4, &self.bend_weft_set),
        ];
        if kind == TriKind::Springs {
            stages.retain(|s| s.1 != 2);
        }
        stages
    }
}

/// The stages' common inputs, and the evaluations they count.
pub(super) struct TriRun<'a> {
    pub targets: &'a [Target],
    pub opts: &'a TriFitOptions,
    pub evaluations: usize,
}

impl TriRun<'_> {
    /// The rms error of `set` at `m`.
    fn cost_of(&mut self, m: &TriMaterial, set: &[usize]) -> f64 {
        cost(m, set, self.targets, &mut self.evaluations).0
    }

    /// Fits one stage's curve `c` over its targets `set` (with control points when
    /// `splines`), then ties the diagonal bending after the weft bending.
    pub(super) fn run_stage(
        &mut self,
        material: &mut TriMaterial,
        (name, c, set): (&str, usize, &[usize]),
        splines: bool,
        progress: &mut dyn FnMut(&str),
    ) {
        if !set.is_empty() {
            let mut say = |line: &str| progress(&format!("{name}: {line}"));
            let cost = stage(
                material,
                c,
                set,
                self.targets,
                &mut self.evaluations,
                splines.then_some(self.opts.max_controls),
                &mut say,
            );
            progress(&format!(
                "{name}: {} control value(s), rms error {:.2} % over {} test(s)",
                material.curves[c].k.len(),
                100.0 * cost,
                set.len()
            ));
        }
        if c == 4 && self.opts.kind != TriKind::Springs {
            tie_diagonal(material);
        }
    }

    /// One more pass over shear and bending (Miguel et al.); the springs' ring-2 bending
    /// springs also carry stretch, so for them the stretch stages are repeated too, until no
    /// value moves by 0.1 % (at most three more passes). A pass that leaves the fitted lab
    /// tests `lab` worse off as a whole is undone: each stage only sees its own tests, and on
    /// a shell's cotton the springs' bending stage can stiffen the ring-2 springs until the
    /// strips are 330–630 % off and a cantilever no longer solves. Returns the lab tests'
    /// rms error at the end.
    pub(super) fn repeat_passes(
        &mut self,
        material: &mut TriMaterial,
        stages: &[(&'static str, usize, &[usize])],
        lab: &[usize],
        notes: &mut Vec<String>,
        progress: &mut dyn FnMut(&str),
    ) -> f64 {
        let springs = self.opts.kind == TriKind::Springs;
        let mut whole = self.cost_of(material, lab);
        let again: Vec<_> = if springs {
            stages.to_vec()
        } else {
            stages.iter().filter(|s| s.1 >= 2).cloned().collect()
        };
        for _ in 0..if springs { 3 } else { 1 } {
            let before = material.clone();
            for &st in &again {
                self.run_stage(material, st, false, progress);
            }
            let now = self.cost_of(material, lab);
            if now.is_nan() || now >= whole {
                progress(&format!(
                    "the pass left the lab tests worse off (rms {:.2} % against {:.2} %): undone",
                    100.0 * now,
                    100.0 * whole
                ));
                notes.push(format!("a repeated pass over the stages was undone: it left the fitted lab tests worse off as a whole ({})", rms_against(now, whole)));
                *material = before;
                break;
            }
            whole = now;
            let moved = (0..6).any(|c| {
                let (a, b) = (&before.curves[c].k, &material.curves[c].k);
                a.iter().zip(b).any(|(x, y)| (x - y).abs() > 1e-3 * x.abs())
            });
            if !moved {
                break;
            }
        }
        whole
    }

    /// Warp and weft bending fitted together; undone unless the lab tests, at rms error
    /// `whole` without it, gain as a whole (the springs' bending also stretches).
    pub(super) fn bending_together(
        &mut self,
        material: &mut TriMaterial,
        sets: &StageSets,
        whole: f64,
        notes: &mut Vec<String>,
        progress: &mut dyn FnMut(&str),
    ) {
        let both: Vec<usize> = sets
            .bend_warp
            .iter()
            .chain(&sets.bend_weft)
            .copied()
            .collect();
        let before = material.clone();
        let mut say = |line: &str| progress(&format!("warp and weft bending together: {line}"));
        let cost = levenberg_marquardt(
            material,
            &[3, 4],
            &both,
            self.targets,
            &mut self.evaluations,
            &mut say,
        );
        progress(&format!(
            "warp and weft bending together: rms error {:.2} % over {} test(s)",
            100.0 * cost,
            both.len()
        ));
        let now = self.cost_of(material, &sets.lab);
        if now.is_nan() || now >= whole {
            notes.push(format!("fitting warp and weft bending together was undone: it left the fitted lab tests worse off as a whole ({})", rms_against(now, whole)));
            *material = before;
        }
    }
}

/// A trial's rms error against the kept one's, for a note; a trial at which a fitted test does
/// not solve (rms not a number) says so.
fn rms_against(trial: f64, kept: f64) -> String {
    if trial.is_finite() {
        format!("rms {:.2} % against {:.2} %", 100.0 * trial, 100.0 * kept)
    } else {
        format!(
            "a fitted test does not solve there; rms {:.2} % kept",
            100.0 * kept
        )
    }
}

#[cfg(test)]
mod tests {
    use super::rms_against;

    #[test]
    fn a_trial_that_does_not_solve_is_said_in_words() {
        assert_eq!(rms_against(0.2, 0.1), "rms 20.00 % against 10.00 %");
        let s = rms_against(f64::NAN, 1.1456);
        assert!(s.contains("does not solve") && !s.contains("NaN"), "{s}");
    }
}
