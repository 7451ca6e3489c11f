//! The mesh check's line in the fit's notes and progress.

use super::{MeshCheck, MESH_ANGLE_TOL_DEG, MESH_PARAM_TOL};
use crate::fit::{Bench, Fitted};

impl Bench<'_, '_> {
    /// The check's line in the notes, a warning when the fit of material `fitted` is not
    /// mesh-independent (a parameter moving by 1 % or more, a curve by 0.3 %, a drape angle
    /// by 0.1°).
    pub(in crate::fit) fn mesh_check_notes(
        &mut self,
        fitted: &Fitted,
        last: (usize, usize),
        m: &MeshCheck,
    ) {
        let bad = !m.passes();
        let law = if m.law_change >= MESH_PARAM_TOL {
            format!(
                "; η's weights and exponents (and a coupling's factors) one by one by up to {:.0} % ({}), which the curves do not pin down",
                100.0 * m.law_change,
                m.law_parameter
            )
        } else {
            String::new()
        };
        let how = if m.solved_on == m.mesh {
            format!("solved on {}x{}", m.mesh.0, m.mesh.1)
        } else {
            format!(
                "estimated from {}x{} at order {}; --mesh-check fine solves on {}x{}",
                m.solved_on.0,
                m.solved_on.1,
                super::mesh_order(self.lab, self.ctx, fitted),
                m.mesh.0,
                m.mesh.1
            )
        };
        let angles = m
            .angle_change_deg
            .map_or(String::new(), |a| format!(", drape angles by {a:.3}°"));
        let own = if self.lab.meshes.any_strip() {
            " (and every strip refined on its own mesh once more)"
        } else {
            ""
        };
        let line = format!(
            "{}mesh check: refining {}x{} to {}x{}{own} would change {} by {:.2} % (the largest change of a determined stiffness, thickness or rigidity, or of the law's tangent stiffness across the tested range), the fitted curves by {:.2} % ({}){angles} (first-order refit, {how}){law}",
            if bad { "warning: " } else { "" },
            last.0,
            last.1,
            m.mesh.0,
            m.mesh.1,
            if m.parameter.is_empty() { "no parameter" } else { &m.parameter },
            100.0 * m.change,
            100.0 * m.curve_change,
            if m.curve.is_empty() { "-" } else { &m.curve },
        );
        // a curve alone failing, where `own` meshes left it: the strict rule refines its strip
        let curve_only = m.change < MESH_PARAM_TOL
            && m.angle_change_deg.is_none_or(|a| a < MESH_ANGLE_TOL_DEG)
            && self.ctx.opts.test_meshes == crate::fit::TestMeshes::Own;
        let line = if bad && curve_only {
            format!("{line}: the fit is not mesh-independent; --test-meshes strict refines the strip of that curve (or add the finer level, --mesh-ladder)")
        } else if bad {
            format!("{line}: the fit is not mesh-independent; add the finer level (--mesh-ladder)")
        } else {
            line
        };
        let each: Vec<String> = m
            .changes
            .iter()
            .map(|(n, c)| format!("{n} {:+.2} %", 100.0 * c))
            .collect();
        self.journal
            .say(&format!("mesh check, each change: {}", each.join(", ")));
        self.journal.say(&line);
        self.journal.note(line);
    }
}
