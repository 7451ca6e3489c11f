//! A tensile stage that fails to solve falls back instead of ending the fit.
//!
//! A stage's first evaluation solves every strip at the stage's start; the minimiser's later
//! trials already back off from a failed solve (a shorter step in the parameters). A start
//! that fails comes from a law the shell cannot hold: one whose stress stops rising a little
//! past the tested strain (the clamped strips reach more than their nominal strain at the
//! jaws' corners) or whose energy overflows there. The stage then starts again:
//!
//! 1. from the same law, every direction cut off below where its stress stops rising
//!    ([`super::plausible::fall_cutoff`]);
//! 2. from the lowest degree with those cut-offs: the stage's η linear (η(x) = x, a quadratic
//!    energy), its stiffness kept; the stage refits η's exponent from there.
//!
//! Each fallback taken is a note. When none solves, the error says what to try.

use super::map::StageMap;
use super::stages::{StageMode, StageRun};
use super::{Bench, FitError, Fitted};
use crate::material::Eta;

/// What to try when a stage fails from every start, for the error message.
const HINT: &str = "the stage failed from its start, from its law cut off where its stress stops rising and from a linear law; try `--max-degree 1`, `--strategy adaptive`, or `ks-fit check` on the dataset (units, toes, force_scale)";

impl Bench<'_, '_> {
    /// One tensile stage on the shell model from material `m` (see
    /// [`Bench::shell_stage_once`]), falling back (module doc) where a full stage of the
    /// ladder fails to solve. Trials (raised degrees,
    /// screened or coupled stages) and the stiffness-alone stages fail as they are: their
    /// callers keep what they had.
    pub(super) fn shell_stage(
        &mut self,
        m: &Fitted,
        map: StageMap,
        strips: &[usize],
        level: (usize, usize),
        strain_range: bool,
        mode: StageMode,
    ) -> Result<StageRun, FitError> {
        let run = self.shell_stage_once(m, map, strips, level, strain_range, mode);
        let falls_back = mode == StageMode::Full && !map.coupling;
        let (stage, source) = match run {
            Err(FitError::Scene { stage, source }) if falls_back => (stage, source),
            other => return other,
        };
        let maps = self.fallback_maps(map);
        for linear in [false, true] {
            let mut law = m.law.clone();
            let mut changed = false;
            for other in &maps {
                let note = super::plausible::cut_before_fall(&mut law, *other);
                changed |= self.journal.law_note(note);
            }
            if linear && map.eta(&law) != &Eta::linear() {
                *map.eta_mut(&mut law) = Eta::linear();
                changed = true;
            }
            if !changed {
                continue;
            }
            let what = if linear {
                "a linear law (the lowest degree), every law cut off where its stress stops rising"
            } else {
                "its law cut off where its stress stops rising"
            };
            let note = format!(
                "{stage} failed to solve from its start ({source}): started again from {what}"
            );
            self.journal.say(&note);
            self.journal.note(note);
            let from = Fitted { law, ..m.clone() };
            if let Ok(done) = self.shell_stage_once(&from, map, strips, level, strain_range, mode) {
                return Ok(done);
            }
        }
        Err(FitError::Stage {
            stage,
            source,
            hint: HINT.into(),
        })
    }

    /// The maps of every direction for the fallback's cut-offs: the stage's own, and the other
    /// two with the stage's x̂ scaled to theirs (the largest tested strain of the fit's
    /// strips, squared; a quarter of it for the shear).
    fn fallback_maps(&self, map: StageMap) -> Vec<StageMap> {
        use super::map::Direction;
        let e2 = self.ctx.prep.strips.iter().map(|s| {
            let e = super::green(s.nodes.last().copied().unwrap_or(0.0), s.length);
            e * e
        });
        let e2 = e2.fold(0.0, f64::max).max(map.xhat);
        [Direction::Warp, Direction::Weft, Direction::Shear]
            .into_iter()
            .map(|dir| StageMap {
                dir,
                xhat: match dir {
                    d if d == map.dir => map.xhat,
                    Direction::Shear => 0.25 * e2,
                    _ => e2,
                },
                c_known: true,
                coupling: false,
                ..map
            })
            .collect()
    }
}
