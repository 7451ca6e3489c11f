//! The shapes' stage of the triangle-model fit: the components a captured shape determines
//! and no lab test does, scanned and then refined (see [`crate::shape`]).

use super::minimise::{levenberg_marquardt, scan};
use super::Target;
use crate::fit::shape_target::SHAPE_TRUST;
use crate::tri::TriMaterial;

/// The components of [`TriMaterial::curves`] by the names of [`super::TriFit::undetermined`].
const COMPONENTS: [&str; 5] = ["warp", "weft", "shear", "bend_warp", "bend_weft"];

/// The shapes' stage: the components the fitted shapes exercise that no lab test determines
/// (named in `undetermined`), fitted to the shapes' residuals. Returns whether the shapes were
/// fitted (otherwise they are predicted, and a note says why).
pub(super) fn shape_stage(
    m: &mut TriMaterial,
    targets: &[Target],
    undetermined: &mut Vec<&'static str>,
    notes: &mut Vec<String>,
    evaluations: &mut usize,
    progress: &mut dyn FnMut(&str),
) -> bool {
    let set: Vec<usize> = (0..targets.len())
        .filter(|&i| matches!(&targets[i], Target::Shape(s) if s.fitted()))
        .collect();
    if set.is_empty() {
        return false;
    }
    let mut comps: Vec<usize> = set
        .iter()
        .flat_map(|&i| match &targets[i] {
            Target::Shape(s) => s.exercised().to_vec(),
            _ => Vec::new(),
        })
        .filter(|&c| undetermined.contains(&COMPONENTS[c]))
        .collect();
    comps.sort_unstable();
    comps.dedup();
    if comps.is_empty() {
        notes.push("the lab tests determine every component the shapes exercise: the shapes are predicted (validation), not fitted".into());
        return false;
    }
    let names: Vec<&str> = comps.iter().map(|&c| COMPONENTS[c]).collect();
    let label = names.join(", ");
    let mut say = |line: &str| progress(&format!("{label} from shapes: {line}"));
    for &c in &comps {
        scan(m, c, &set, targets, evaluations, &mut say);
    }
    let cost = levenberg_marquardt(m, &comps, &set, targets, evaluations, &mut say);
    progress(&format!(
        "{} from {} shape(s): rms error {:.2} %",
        names.join(", "),
        set.len(),
        100.0 * cost
    ));
    undetermined.retain(|n| !names.contains(n));
    notes.push(format!(
        "{} fitted to the captured shape(s), which no lab test here determines",
        names.join(", ")
    ));
    for &i in &set {
        if let Target::Shape(s) = &targets[i] {
            let e = s.errors(m);
            if e.error.is_nan() || e.error >= SHAPE_TRUST {
                notes.push(format!(
                    "WARNING: the model does not reproduce the shape {} ({}: error {:.0} % at the optimum, rms distance {:.2} mm): {} fitted to it are not trustworthy (a sheet that buckles can settle on another branch of wrinkles in another model or mesh)",
                    s.test.obj.display(),
                    e.descriptor,
                    100.0 * e.error,
                    1e3 * e.rms_distance,
                    names.join(", ")
                ));
            }
        }
    }
    true
}
