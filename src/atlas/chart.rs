//! The atlas chart: solve time against case, one line per method (log scale; failures drawn at
//! the top edge as crosses).

use super::{Case, Row};

/// SVG of seconds against case for every method in `rows`.
pub fn to_svg(rows: &[Row]) -> Result<String, String> {
    use plotters::prelude::*;
    let mut cases: Vec<Case> = Vec::new();
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !cases.contains(&r.case) {
            cases.push(r.case);
        }
        if !names.contains(&r.method) {
            names.push(r.method);
        }
    }
    let times = || rows.iter().map(|r| r.seconds).filter(|t| *t > 0.0);
    let lo = times().fold(f64::INFINITY, f64::min).min(1.0) * 0.5;
    let hi = times().fold(0.0f64, f64::max).max(lo * 4.0) * 2.0;
    let labels: Vec<String> = cases.iter().map(|c| c.label()).collect();
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (1000, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Stability atlas: solve time per case (crosses: did not converge)",
                ("sans-serif", 18),
            )
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5..cases.len() as f64 - 0.5, (lo..hi).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_labels(cases.len())
            .x_label_formatter(&|v| {
                let i = v.round();
                if (v - i).abs() < 1e-6 && i >= 0.0 {
                    labels.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_desc("seconds")
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, name) in names.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            let pts: Vec<(f64, f64, bool)> = cases
                .iter()
                .enumerate()
                .filter_map(|(i, c)| {
                    rows.iter()
                        .find(|r| r.case == *c && r.method == *name)
                        .map(|r| (i as f64, r.seconds.max(lo), r.converged))
                })
                .collect();
            let ok: Vec<(f64, f64)> = pts.iter().filter(|p| p.2).map(|p| (p.0, p.1)).collect();
            chart
                .draw_series(LineSeries::new(ok.clone(), color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(*name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            chart
                .draw_series(ok.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| e.to_string())?;
            chart
                .draw_series(
                    pts.iter()
                        .filter(|p| !p.2)
                        .map(|p| Cross::new((p.0, hi / 1.5), 6, color.stroke_width(2))),
                )
                .map_err(|e| e.to_string())?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}
