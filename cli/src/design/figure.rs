//! The design's figure: per run (a column each) the planned inputs (as a
//! share of their ranges), the nominal states, and each held sign argument
//! with its band shaded, and the nominal track over ground with the
//! trial area; below, the predicted relative standard errors of
//! θ against run length (log–log), the budget marked.

use crate::plot::{Figure, MODEL_COLOURS, decimate_to, save as save_figure, styled_mesh};
use leeway_design::report::Design;
use leeway_design::trial::margins;
use leeway_model::Interpreter;
use leeway_model::model::Model;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// The line colours, as every figure of leeway draws them.
const COLOURS: [RGBColor; 6] = MODEL_COLOURS;
/// Runs drawn (a design rarely needs more).
const MAX_RUNS: usize = 4;
const ROW: u32 = 240;
/// Seconds of excitation an input panel shows.
const WINDOW: f64 = 120.0;

struct DesignFigure<'a> {
    model: &'a Interpreter,
    design: &'a Design,
}

/// Draws the figure into `path` (`.png` a bitmap, else SVG).
pub fn save(path: &Path, model: &Interpreter, design: &Design) -> Result<(), String> {
    save_figure(path, &DesignFigure { model, design })
}

impl Figure for DesignFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let runs = self.design.runs.len().clamp(1, MAX_RUNS) as u32;
        (520 * runs.max(2), 5 * ROW)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (top, bottom) = root.split_vertically(4 * ROW);
        let runs = self.design.runs.len().clamp(1, MAX_RUNS);
        let columns = top.split_evenly((4, runs));
        for (e, _) in self.design.runs.iter().enumerate().take(runs) {
            self.inputs(&columns[e], e)?;
            self.states(&columns[runs + e], e)?;
            self.margins(&columns[2 * runs + e], e)?;
            self.track(&columns[3 * runs + e], e)?;
        }
        self.accuracy(&bottom)
    }
}

type Area<'a, DB> = DrawingArea<DB, Shift>;

impl DesignFigure<'_> {
    fn time(&self, n: usize) -> Vec<f64> {
        (0..n).map(|k| k as f64 * self.design.step).collect()
    }

    fn lines<DB: DrawingBackend>(
        &self,
        area: &Area<'_, DB>,
        title: &str,
        y_desc: &str,
        series: &[(String, Vec<f64>)],
        band: Option<f64>,
    ) -> Result<(), String> {
        let n = series.first().map_or(0, |s| s.1.len());
        let t = self.time(n);
        let pts: Vec<Vec<(f64, f64)>> =
            series.iter().map(|s| decimate_to(&t, &s.1, 1500)).collect();
        let (mut lo, mut hi) = pts
            .iter()
            .flatten()
            .filter(|p| p.1.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p.1), h.max(p.1))
            });
        if let Some(b) = band {
            lo = lo.min(-0.1 * b);
            hi = hi.max(1.1 * b);
        }
        if !lo.is_finite() || hi <= lo {
            (lo, hi) = (lo.min(0.0) - 1.0, hi.max(0.0) + 1.0);
        }
        let pad = 0.05 * (hi - lo);
        let x_max = t.last().copied().unwrap_or(1.0).max(self.design.step);
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 17))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(58)
            .build_cartesian_2d(0.0..x_max, (lo - pad)..(hi + pad))
            .map_err(|e| e.to_string())?;
        styled_mesh(&mut chart, "time (s)", y_desc)
            .draw()
            .map_err(|e| e.to_string())?;
        if let Some(b) = band {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(0.0, lo - pad), (x_max, b)],
                    RGBColor(214, 39, 40).mix(0.12).filled(),
                )))
                .map_err(|e| e.to_string())?;
        }
        for (i, (s, p)) in series.iter().zip(&pts).enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            chart
                .draw_series(LineSeries::new(p.iter().copied(), colour.stroke_width(1)))
                .map_err(|e| e.to_string())?
                .label(s.0.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 13))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK.mix(0.2))
            .draw()
            .map_err(|e| e.to_string())
    }

    /// The inputs over a window a person can read (the first
    /// [`WINDOW`] s), each labelled with its whole-run mean and spread.
    fn inputs<DB: DrawingBackend>(&self, area: &Area<'_, DB>, e: usize) -> Result<(), String> {
        let ir = self.model.ir();
        let c = self.design.conditions.as_ref().ok_or("no conditions")?;
        let run = &self.design.runs[e];
        let n = run.inputs.len();
        let shown = n.min(((WINDOW / self.design.step).ceil() as usize).max(2));
        let series: Vec<(String, Vec<f64>)> = ir
            .inputs
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let l = c.limits[i];
                let all: Vec<f64> = run
                    .inputs
                    .iter()
                    .map(|u| 100.0 * (u[i] - l.low) / l.span())
                    .collect();
                let mean = all.iter().sum::<f64>() / all.len().max(1) as f64;
                let sd = (all.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>()
                    / all.len().max(1) as f64)
                    .sqrt();
                (
                    format!("{name}: mean {mean:.0} %, sd {sd:.0} %"),
                    all[..shown].to_vec(),
                )
            })
            .collect();
        let title = format!(
            "run {} {}: inputs, first {} s of {} s",
            e + 1,
            self.design.experiments[e].pattern,
            (shown as f64 * self.design.step).round(),
            (n as f64 * self.design.step).round()
        );
        self.lines(area, &title, "% of range", &series, None)
    }

    /// The run's nominal track over ground (north up, east right), the
    /// mean current's drift included, and the trial area when the plan
    /// gives one.
    fn track<DB: DrawingBackend>(&self, area: &Area<'_, DB>, e: usize) -> Result<(), String> {
        let Some(t) = self.design.experiments[e].track.as_ref() else {
            return Ok(());
        };
        let radius = self.design.conditions.as_ref().and_then(|c| c.area_radius);
        let area_box = self.design.conditions.as_ref().and_then(|c| c.area_box);
        // The box's finite sides count towards the view, as the circle does.
        let box_reach = area_box.map_or(0.0, |b| {
            [b.north, b.east]
                .iter()
                .flatten()
                .filter(|x| x.is_finite())
                .fold(0.0f64, |r, x| r.max(x.abs()))
        });
        let reach = radius
            .unwrap_or(0.0)
            .max(box_reach)
            .max(t.farthest)
            .max(1.0)
            * 1.1;
        let (w, h) = area.dim_in_pixel();
        let wide = reach
            * (f64::from(w.saturating_sub(66)) / f64::from(h.saturating_sub(76).max(1))).max(1.0);
        let step = (t.positions.len() / 1500).max(1);
        let pts: Vec<(f64, f64)> = t
            .positions
            .iter()
            .step_by(step)
            .map(|p| (p[1], p[0]))
            .collect();
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "run {}: nominal track, ends {:.0} m from the start",
                    e + 1,
                    t.end[0].hypot(t.end[1])
                ),
                ("sans-serif", 17),
            )
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(58)
            // Metres alike on both axes: the plot area is wider than tall.
            .build_cartesian_2d(-wide..wide, -reach..reach)
            .map_err(|e| e.to_string())?;
        styled_mesh(&mut chart, "east (m)", "north (m)")
            .draw()
            .map_err(|e| e.to_string())?;
        if let Some(r) = radius {
            let circle: Vec<(f64, f64)> = (0..=120)
                .map(|k| {
                    let a = f64::from(k) * std::f64::consts::TAU / 120.0;
                    (r * a.sin(), r * a.cos())
                })
                .collect();
            chart
                .draw_series(LineSeries::new(circle, BLACK.mix(0.5).stroke_width(2)))
                .map_err(|e| e.to_string())?;
        }
        if let Some(b) = area_box {
            // A side not given runs off the view: a channel.
            let clip = |x: f64, limit: f64| x.clamp(-limit, limit);
            let (s, n) = (clip(b.north[0], reach), clip(b.north[1], reach));
            let (w, e) = (clip(b.east[0], wide), clip(b.east[1], wide));
            let outline = vec![(w, s), (w, n), (e, n), (e, s), (w, s)];
            chart
                .draw_series(LineSeries::new(outline, BLACK.mix(0.5).stroke_width(2)))
                .map_err(|e| e.to_string())?;
        }
        chart
            .draw_series(LineSeries::new(pts, COLOURS[1].stroke_width(1)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(std::iter::once(Circle::new((0.0, 0.0), 4, BLACK.filled())))
            .map_err(|e| e.to_string())?;
        Ok(())
    }

    fn states<DB: DrawingBackend>(&self, area: &Area<'_, DB>, e: usize) -> Result<(), String> {
        let ir = self.model.ir();
        let truth = &self.design.nominal[e];
        let series: Vec<(String, Vec<f64>)> = ir
            .states
            .iter()
            .cloned()
            .zip(truth.states.iter().cloned())
            .collect();
        self.lines(
            area,
            &format!("run {}: nominal states", e + 1),
            "state",
            &series,
            None,
        )
    }

    fn margins<DB: DrawingBackend>(&self, area: &Area<'_, DB>, e: usize) -> Result<(), String> {
        let held = &self.design.held[e];
        if held.is_empty() {
            return self.lines(area, &format!("run {}: no sign held", e + 1), "", &[], None);
        }
        let run = &self.design.runs[e];
        let values = margins(self.model, &self.design.nominal[e], &run.inputs, held);
        let series: Vec<(String, Vec<f64>)> = held
            .iter()
            .zip(values)
            .map(|(h, v)| {
                let side = if h.sign < 0.0 { "−" } else { "+" };
                (
                    format!("{side}{}", h.name),
                    v.iter().map(|m| m + h.band).collect(),
                )
            })
            .collect();
        let band = held.iter().map(|h| h.band).fold(0.0, f64::max);
        self.lines(
            area,
            &format!("run {}: held signs (band shaded)", e + 1),
            "sign·argument",
            &series,
            Some(band),
        )
    }

    fn accuracy<DB: DrawingBackend>(&self, area: &Area<'_, DB>) -> Result<(), String> {
        let Some(p) = &self.design.prediction else {
            return Ok(());
        };
        let curve: Vec<(f64, Vec<f64>)> = p
            .curve
            .iter()
            .map(|c| {
                let rel = c
                    .std_errors
                    .iter()
                    .zip(&p.parameters)
                    .map(|(s, q)| match s {
                        Some(s) if q.nominal != 0.0 => 100.0 * s / q.nominal.abs(),
                        _ => f64::NAN,
                    })
                    .collect();
                (c.seconds, rel)
            })
            .collect();
        let all = curve
            .iter()
            .flat_map(|c| c.1.iter())
            .filter(|v| v.is_finite() && **v > 0.0);
        let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
        if !lo.is_finite() {
            return Ok(());
        }
        let (x0, x1) = (
            curve.first().map_or(1.0, |c| c.0),
            curve.last().map_or(2.0, |c| c.0),
        );
        // The legend beside the chart, in as many columns as it needs: it
        // fits however many parameters the model has.
        let (w, _) = area.dim_in_pixel();
        let (area, key) = area.split_horizontally(w.saturating_sub(LEGEND));
        let mut chart = ChartBuilder::on(&area)
            .caption(
                "predicted relative standard error of θ against run length",
                ("sans-serif", 17),
            )
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(58)
            .build_cartesian_2d(
                (x0..x1.max(x0 * 1.01)).log_scale(),
                (lo * 0.8..hi * 1.25).log_scale(),
            )
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("seconds per experiment")
            .y_desc("σ/|θ| (%)")
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(BLACK.mix(0.04))
            .bold_line_style(BLACK.mix(0.12))
            .draw()
            .map_err(|e| e.to_string())?;
        let mut entries: Vec<(String, RGBColor)> = Vec::new();
        for (i, q) in p.parameters.iter().enumerate() {
            let pts: Vec<(f64, f64)> = curve
                .iter()
                .map(|c| (c.0, c.1[i]))
                .filter(|pt| pt.1.is_finite() && pt.1 > 0.0)
                .collect();
            if pts.is_empty() {
                continue;
            }
            let colour = colour(i, p.parameters.len());
            chart
                .draw_series(LineSeries::new(pts, colour.stroke_width(1)))
                .map_err(|e| e.to_string())?;
            entries.push((q.name.clone(), colour));
        }
        let budget = self.design.seconds;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(budget, lo * 0.8), (budget, hi * 1.25)],
                BLACK.mix(0.5).stroke_width(1),
            )))
            .map_err(|e| e.to_string())?;
        entries.push(("budget".into(), RGBColor(128, 128, 128)));
        legend(&key, &entries)
    }
}

/// Pixels beside the accuracy chart for its legend.
const LEGEND: u32 = 220;

/// Line `i` of `n`: leeway's six colours when they suffice, else `n`
/// hues evenly round the colour wheel, so no two lines share one.
fn colour(i: usize, n: usize) -> RGBColor {
    if n <= COLOURS.len() {
        return COLOURS[i];
    }
    let rgb = HSLColor(i as f64 / n as f64, 0.75, 0.42)
        .to_backend_color()
        .rgb;
    RGBColor(rgb.0, rgb.1, rgb.2)
}

/// A legend of `entries` filling `area` column by column.
fn legend<DB: DrawingBackend>(
    area: &Area<'_, DB>,
    entries: &[(String, RGBColor)],
) -> Result<(), String> {
    const LINE: i32 = 16;
    let (w, h) = area.dim_in_pixel();
    let rows = ((i32::try_from(h).unwrap_or(i32::MAX) - 2 * LINE) / LINE).max(1) as usize;
    let columns = entries.len().div_ceil(rows).max(1);
    let width = i32::try_from(w as usize / columns).unwrap_or(i32::MAX);
    for (k, (name, colour)) in entries.iter().enumerate() {
        let x = i32::try_from(k / rows).unwrap_or(0) * width + 4;
        let y = LINE + i32::try_from(k % rows).unwrap_or(0) * LINE;
        area.draw(&PathElement::new(
            vec![(x, y + LINE / 2), (x + 16, y + LINE / 2)],
            colour.stroke_width(2),
        ))
        .map_err(|e| e.to_string())?;
        area.draw(&Text::new(
            name.clone(),
            (x + 20, y + 2),
            ("sans-serif", 12),
        ))
        .map_err(|e| e.to_string())?;
    }
    Ok(())
}
