//! The atlas as CSV and Markdown, the one-line accounts of each row, and the per-case summary
//! of iterations against the best strategy.

use super::{Case, Row};
use crate::scene::SceneError;
use crate::solve::{SolveError, SolveReport};
use std::fmt::Write;

/// Why a solve failed, in one line: indefinite, ascent / line-search collapse, stagnation
/// (the budget ran out), or the law's domain.
pub fn explain(e: &SceneError) -> String {
    match e {
        SceneError::Solve { stage, source } => {
            let why = match source {
                SolveError::Indefinite { residual } => format!(
                    "indefinite: the Hessian lost positive definiteness and plain Newton has no fallback (residual {residual:.1e})"
                ),
                SolveError::Stalled { residual } => format!(
                    "line-search collapse: no step along the search direction lowers the energy (residual {residual:.1e})"
                ),
                SolveError::NotConverged {
                    iterations,
                    residual,
                    ..
                } => format!(
                    "stagnation: {iterations} iterations did not reach the tolerance (residual {residual:.1e})"
                ),
                SolveError::StartOutOfDomain(s) => format!("left the law's domain ({s})"),
                other => other.to_string(),
            };
            format!("{stage}: {why}")
        }
        other => other.to_string(),
    }
}

/// What a converged row needed, in one line.
pub(super) fn what_happened(row: &Row, solves: &[SolveReport]) -> String {
    let mut parts = Vec::new();
    let f = solves.iter().fold([0usize; 4], |a, r| {
        [
            a[0] + r.fallbacks.indefinite,
            a[1] + r.fallbacks.ascent,
            a[2] + r.fallbacks.stagnation,
            a[3] + r.fallbacks.short_step,
        ]
    });
    if row.backward_euler_steps > 0 {
        let names = ["indefinite", "ascent", "stagnation", "short step"];
        let why: Vec<String> = names
            .iter()
            .zip(f)
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        parts.push(format!(
            "backward Euler {} ({})",
            row.backward_euler_steps,
            why.join(", ")
        ));
    }
    let curvature: usize = solves.iter().map(|r| r.curvature_steps).sum();
    if curvature > 0 {
        parts.push(format!("{curvature} negative-curvature steps"));
    }
    let convexified: usize = solves.iter().map(|r| r.convexified_steps).sum();
    if convexified > 0 {
        parts.push(format!("{convexified} convexified steps"));
    }
    if solves.iter().any(|r| r.trust_region_gave_up) {
        parts.push("trust region gave up, line search finished".into());
    }
    if row.saddle_escapes > 0 {
        parts.push(format!("{} saddle escapes", row.saddle_escapes));
    }
    if parts.is_empty() {
        "no fallback".into()
    } else {
        parts.join("; ")
    }
}

/// CSV with header `case,method,converged,stable,relative_residual,iterations,backward_euler_steps,refinement_steps,saddle_escapes,seconds,note,factorizations,load_steps,drape_angle_deg`
/// (the last empty for strips).
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "case,method,converged,stable,relative_residual,iterations,backward_euler_steps,refinement_steps,saddle_escapes,seconds,note,factorizations,load_steps,drape_angle_deg\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "\"{}\",\"{}\",{},{},{:e},{},{},{},{},{:.3},\"{}\",{},{},{}",
            r.case.name(),
            r.method,
            r.converged,
            r.stable,
            r.residual,
            r.iterations,
            r.backward_euler_steps,
            r.refinement_steps,
            r.saddle_escapes,
            r.seconds,
            r.note.replace('"', "'"),
            r.factorizations,
            r.load_steps,
            r.drape_angle_deg
                .map_or(String::new(), |a| format!("{a:.6}"))
        );
    }
    s
}

/// A Markdown table of the same.
pub fn to_markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| case | method | converged | stable | relative residual | iterations | factorisations | load steps | backward-Euler steps | refinement steps | saddle escapes | seconds | drape ° | what happened |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {} | {} |",
            r.case.name(),
            r.method,
            if r.converged { "yes" } else { "**no**" },
            match (r.converged, r.stable) {
                (false, _) => "–",
                (true, true) => "yes",
                (true, false) => "**saddle**",
            },
            if r.converged {
                format!("{:.1e}", r.residual)
            } else {
                "–".into()
            },
            count(r, r.iterations),
            count(r, r.factorizations),
            count(r, r.load_steps),
            count(r, r.backward_euler_steps),
            count(r, r.refinement_steps),
            count(r, r.saddle_escapes),
            r.seconds,
            r.drape_angle_deg
                .filter(|_| r.converged)
                .map_or("–".into(), |a| format!("{a:.4}")),
            r.note.replace('|', "/")
        );
    }
    s
}

/// A count of a converged row; a failed row's counts are unknown (the failed solve's report is
/// lost with it), shown as –.
fn count(r: &Row, n: usize) -> String {
    if r.converged {
        n.to_string()
    } else {
        "–".into()
    }
}

/// Per case: each strategy's iterations as a multiple of the fewest any converged strategy took
/// (the strategies only: plain Newton and the precision variants left out).
pub fn summary(rows: &[Row]) -> String {
    let strategies: Vec<&str> = crate::solve::Strategy::ALL.iter().map(|s| s.0).collect();
    let mut s = String::from("| case | fewest iterations |");
    for n in &strategies {
        let _ = write!(s, " {n} |");
    }
    s.push_str("\n|---|---|");
    s.push_str(&"---|".repeat(strategies.len()));
    s.push('\n');
    let mut cases: Vec<Case> = Vec::new();
    for r in rows {
        if !cases.contains(&r.case) {
            cases.push(r.case);
        }
    }
    for case in cases {
        let of = |m: &str| rows.iter().find(|r| r.case == case && r.method == m);
        let best = strategies
            .iter()
            .filter_map(|m| of(m).filter(|r| r.converged).map(|r| r.iterations))
            .min();
        let _ = write!(
            s,
            "| {} | {} |",
            case.name(),
            best.map_or("–".into(), |b| b.to_string())
        );
        for m in &strategies {
            let cell = match (of(m), best) {
                (Some(r), Some(b)) if r.converged => {
                    format!(
                        "{:.2}× ({:.2} s)",
                        r.iterations as f64 / b.max(1) as f64,
                        r.seconds
                    )
                }
                (Some(_), _) => "failed".into(),
                (None, _) => "–".into(),
            };
            let _ = write!(s, " {cell} |");
        }
        s.push('\n');
    }
    s
}
