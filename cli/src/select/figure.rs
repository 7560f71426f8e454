//! `leeway select --plot`: the path's criteria against model size. Above,
//! Hansen's J and the score `J − d·ln N` the stopping rule minimises, as
//! `sign·log10(1 + |x|)` (J spans orders of magnitude once a true term is
//! dropped, and the score goes negative); below, the held-out free-run
//! criterion. The chosen model is circled, each point names the candidate
//! dropped to reach it.

use crate::plot::{Figure, MODEL_COLOURS, save, styled_mesh};
use leeway_select::Selection;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const WIDTH: u32 = 1000;
const PANEL: u32 = 340;

struct SelectionFigure<'a>(&'a Selection);

/// Draws the figure into `path` (`.png` a bitmap, else SVG).
pub fn draw(path: &Path, selection: &Selection) -> Result<(), String> {
    save(path, &SelectionFigure(selection))
}

/// `sign(x)·log10(1 + |x|)`: linear near 0, logarithmic beyond.
fn signed_log(x: f64) -> f64 {
    x.signum() * x.abs().ln_1p() / std::f64::consts::LN_10
}

impl SelectionFigure<'_> {
    fn has_criterion(&self) -> bool {
        self.0.steps.iter().any(|s| s.criterion.is_some())
    }

    /// One panel: each series as (legend, points (size, value)); the
    /// chosen step circled on the first.
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        title: &str,
        y_desc: &str,
        series: &[(&str, Vec<Option<f64>>)],
    ) -> Result<(), String> {
        let s = self.0;
        let size: Vec<f64> = s.steps.iter().map(|st| st.size as f64).collect();
        let finite = series
            .iter()
            .flat_map(|(_, v)| v.iter().flatten())
            .copied()
            .filter(|v| v.is_finite());
        let (mut lo, mut hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
        if !lo.is_finite() || hi <= lo {
            (lo, hi) = (lo.min(0.0) - 1.0, hi.max(0.0) + 1.0);
        }
        let pad = 0.08 * (hi - lo);
        let x_max = size.iter().copied().fold(1.0, f64::max);
        // Candidates kept fall from left to right, as the path drops them.
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 17))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d((x_max + 0.5)..-0.5, (lo - pad)..(hi + pad))
            .map_err(|e| e.to_string())?;
        styled_mesh(&mut chart, "candidates kept", y_desc)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, (name, values)) in series.iter().enumerate() {
            let colour = MODEL_COLOURS[i % MODEL_COLOURS.len()];
            let points: Vec<(f64, f64)> = size
                .iter()
                .zip(values)
                .filter_map(|(&x, v)| v.filter(|v| v.is_finite()).map(|v| (x, v)))
                .collect();
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    colour.stroke_width(2),
                ))
                .map_err(|e| e.to_string())?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| e.to_string())?;
        }
        if let Some((_, values)) = series.first()
            && let Some(v) = values.get(s.chosen).copied().flatten()
        {
            let at = (size[s.chosen], v);
            chart
                .draw_series(std::iter::once(Circle::new(at, 11, BLACK.stroke_width(2))))
                .map_err(|e| e.to_string())?
                .label(format!(
                    "chosen: {} of {} candidates",
                    s.kept.len(),
                    s.candidates.len()
                ))
                .legend(|(x, y)| Circle::new((x + 8, y), 6, BLACK.stroke_width(2)));
            for (k, st) in s.steps.iter().enumerate() {
                // Labels beside their points, off the markers (a step whose
                // free run is not finite has none).
                if let (Some(d), Some(v)) = (&st.dropped, values[k].filter(|v| v.is_finite())) {
                    chart
                        .draw_series(std::iter::once(
                            EmptyElement::at((size[k], v))
                                + Text::new(format!("−{d}"), (6, -16), ("sans-serif", 12)),
                        ))
                        .map_err(|e| e.to_string())?;
                }
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 13))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK.mix(0.2))
            .draw()
            .map_err(|e| e.to_string())
    }
}

impl Figure for SelectionFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let panels = if self.has_criterion() { 2 } else { 1 };
        (WIDTH, panels * PANEL)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let steps = &self.0.steps;
        let score = steps.iter().map(|s| Some(signed_log(s.score))).collect();
        let j = steps.iter().map(|s| Some(signed_log(s.j))).collect();
        let top_series = [("J − d·ln N (the rule's score)", score), ("Hansen's J", j)];
        let title = "Over-identification along the path: sign·log10(1 + |x|)";
        if self.has_criterion() {
            let (top, bottom) = root.split_vertically(PANEL);
            self.panel(&top, title, "sign·log10(1 + |x|)", &top_series)?;
            let criterion = steps.iter().map(|s| s.criterion).collect();
            self.panel(
                &bottom,
                &format!("Held-out free-run criterion ({})", self.0.held_out),
                "1 − fit/100",
                &[("held-out criterion", criterion)],
            )
        } else {
            self.panel(root, title, "sign·log10(1 + |x|)", &top_series)
        }
    }
}
