//! The study's figures, each as SVG and PNG: per case the fit against N
//! (the paper's Figures 2 and 3: one panel per output, one line per
//! estimator, mean ± 1 std as ▲ ▼, the axis held to 0–100), the track of one
//! estimation experiment (the circle with zigzags), and per case one
//! validation run (the true undisturbed outputs against the four models of
//! run 0 at the largest N).

use crate::plot::{
    Figure, clip_band, save, split_sharp, styled_mesh, tick, tick_decimals, y_range,
};
use crate::reproduce::report::Report;
use leeway_model::Experiment;
use leeway_model::Model;
use leeway_model::Source;
use leeway_model::simulate::Disturbances;
use leeway_model::simulate::simulate;
use leeway_scenarios::design::track;
use leeway_scenarios::study;
use leeway_scenarios::study::ESTIMATORS;
use leeway_scenarios::study::OUTPUTS;
use plotters::coord::Shift;
use plotters::prelude::*;

/// One colour per estimator (LS, IV1, IV2, IV3; Okabe–Ito, readable in
/// grey and by colour-blind readers).
const COLOURS: [RGBColor; 4] = [
    RGBColor(0x22, 0x22, 0x22),
    RGBColor(0xCC, 0x79, 0xA7),
    RGBColor(0x00, 0x72, 0xB2),
    RGBColor(0xD5, 0x5E, 0x00),
];

/// Output names with their symbols and units.
const AXES: [(&str, &str); 3] = [
    ("surge u", "m/s"),
    ("sway v", "m/s"),
    ("yaw rate r", "rad/s"),
];

const WIDTH: u32 = 1000;
const FONT: &str = "sans-serif";

/// Any of the study's figures.
pub enum AnyFigure {
    /// Fit against N.
    Fit(FitFigure),
    /// The track of one experiment per case.
    Track(TrackFigure),
    /// One validation run.
    Validation(ValidationFigure),
}

impl AnyFigure {
    /// Draws the figure into `path` (PNG or SVG by extension).
    pub fn save(&self, path: &std::path::Path) -> Result<(), String> {
        match self {
            AnyFigure::Fit(f) => save(path, f),
            AnyFigure::Track(f) => save(path, f),
            AnyFigure::Validation(f) => save(path, f),
        }
    }
}

/// Every figure of a report, with its file name (without extension).
pub fn all(model: &dyn Model, report: &Report) -> Vec<(String, AnyFigure)> {
    let cfg = &report.outcomes.config;
    let mut figures = Vec::new();
    for case in &cfg.cases {
        if let Some(f) = FitFigure::new(report, &case.name) {
            figures.push((format!("fit-{}", case.name), AnyFigure::Fit(f)));
        }
    }
    figures.push((
        "trajectory".to_string(),
        AnyFigure::Track(TrackFigure::new(report)),
    ));
    let validation = study::validation_experiment(model, cfg.validation_len);
    for (c, case) in cfg.cases.iter().enumerate() {
        figures.push((
            format!("validation-{}", case.name),
            AnyFigure::Validation(ValidationFigure::new(model, report, c, &validation)),
        ));
    }
    figures
}

type Error<DB> = DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>;

fn e<DB: DrawingBackend>(err: Error<DB>) -> String {
    err.to_string()
}

/// Greedy word wrap at `width` characters.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Title (bold) and a legend of the four estimators in a strip above the
/// panels, so that no legend hides data.
fn header<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    reference: Option<&str>,
    triangles: bool,
) -> Result<(), String> {
    area.draw(&Text::new(
        title.to_string(),
        (20, 12),
        (FONT, 22).into_font().style(FontStyle::Bold),
    ))
    .map_err(e::<DB>)?;
    let y = 62;
    let mut x = 24;
    let label = (FONT, 17).into_font();
    if let Some(name) = reference {
        area.draw(&PathElement::new(
            vec![(x, y), (x + 34, y)],
            ShapeStyle::from(&BLACK.mix(0.35)).stroke_width(5),
        ))
        .map_err(e::<DB>)?;
        area.draw(&Text::new(name.to_string(), (x + 42, y - 9), label.clone()))
            .map_err(e::<DB>)?;
        x += 60 + 9 * i32::try_from(name.len()).unwrap_or(20);
    }
    for (name, colour) in ESTIMATORS.iter().zip(COLOURS) {
        let style = ShapeStyle::from(&colour).stroke_width(2);
        area.draw(&PathElement::new(vec![(x, y), (x + 34, y)], style))
            .map_err(e::<DB>)?;
        if triangles {
            area.draw(&Circle::new((x + 17, y), 4, colour.filled()))
                .map_err(e::<DB>)?;
        }
        area.draw(&Text::new(name.to_string(), (x + 42, y - 9), label.clone()))
            .map_err(e::<DB>)?;
        x += 110;
    }
    if triangles {
        let grey = BLACK.mix(0.7);
        area.draw(&up(x + 6, y, grey.filled())).map_err(e::<DB>)?;
        area.draw(&down(x + 22, y, grey.filled()))
            .map_err(e::<DB>)?;
        area.draw(&Text::new(
            "mean ± 1 standard deviation".to_string(),
            (x + 36, y - 9),
            label,
        ))
        .map_err(e::<DB>)?;
    }
    Ok(())
}

/// ▲ centred at a pixel.
fn up(x: i32, y: i32, style: ShapeStyle) -> Polygon<(i32, i32)> {
    Polygon::new(vec![(x, y - 6), (x - 6, y + 4), (x + 6, y + 4)], style)
}

/// ▼ centred at a pixel.
fn down(x: i32, y: i32, style: ShapeStyle) -> Polygon<(i32, i32)> {
    Polygon::new(vec![(x, y + 6), (x - 6, y - 4), (x + 6, y - 4)], style)
}

/// Fit against N for one case.
pub struct FitFigure {
    case: String,
    wind: f64,
    runs: usize,
    n: Vec<usize>,
    /// Per estimator, per output: (mean, std) per N.
    series: Vec<[Vec<(f64, f64)>; 3]>,
    /// What is not shown (means outside 0–100 or undefined).
    hidden: Vec<String>,
}

impl FitFigure {
    fn new(report: &Report, case: &str) -> Option<FitFigure> {
        let summary = report.summaries.get(case)?;
        let mut series = Vec::new();
        let mut hidden = Vec::new();
        for est in ESTIMATORS {
            let s = summary.estimators.get(est)?;
            let per_output = OUTPUTS.map(|o| {
                let mean = s.fit_mean.get(o).cloned().unwrap_or_default();
                let std = s.fit_std.get(o).cloned().unwrap_or_default();
                mean.into_iter().zip(std).collect::<Vec<(f64, f64)>>()
            });
            for (o, points) in OUTPUTS.iter().zip(&per_output) {
                let (mut below, mut above, mut undefined) = (Vec::new(), Vec::new(), Vec::new());
                for ((m, _), n) in points.iter().zip(&summary.n) {
                    if !m.is_finite() {
                        undefined.push(n.to_string());
                    } else if *m < 0.0 {
                        below.push(n.to_string());
                    } else if *m > 100.0 {
                        above.push(n.to_string());
                    }
                }
                let all = |v: &Vec<String>| {
                    if v.len() == summary.n.len() && v.len() > 1 {
                        "every N".to_string()
                    } else {
                        format!("N = {}", v.join(", "))
                    }
                };
                if !below.is_empty() {
                    hidden.push(format!("{est} {o} below 0 at {}", all(&below)));
                }
                if !above.is_empty() {
                    hidden.push(format!("{est} {o} above 100 at {}", all(&above)));
                }
                if !undefined.is_empty() {
                    hidden.push(format!(
                        "{est} {o} undefined (every run diverged) at {}",
                        all(&undefined)
                    ));
                }
            }
            series.push(per_output);
        }
        Some(FitFigure {
            case: case.to_string(),
            wind: summary.wind,
            runs: report.outcomes.config.runs,
            n: summary.n.clone(),
            series,
            hidden,
        })
    }

    fn caption(&self) -> String {
        let shown = if self.hidden.is_empty() {
            "every mean lies within 0–100.".to_string()
        } else {
            format!("not shown: {}.", self.hidden.join("; "))
        };
        format!(
            "Mean validation fit over {} Monte Carlo runs at each N (dots joined by lines), ▲ ▼ mean ± 1 standard deviation; \
             the estimators are set slightly apart along N so their markers do not overlap. As in the paper, the axis is held \
             to fits between 0 and 100: a mean outside is marked by an arrowhead on the edge it left by, without its ▲ ▼; {shown}",
            self.runs
        )
    }
}

const FIT_HEAD: u32 = 90;
const FIT_PANEL: u32 = 300;

impl Figure for FitFigure {
    fn size(&self) -> (u32, u32) {
        let foot = 24 * u32::try_from(wrap(&self.caption(), 120).len()).unwrap_or(4) + 20;
        (WIDTH, FIT_HEAD + 3 * FIT_PANEL + foot)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(e::<DB>)?;
        let (head, rest) = root.split_vertically(FIT_HEAD);
        let (body, foot) = rest.split_vertically(3 * FIT_PANEL);
        header(
            &head,
            &format!(
                "Validation fit against N, {} wind (mean wind {} m/s north and east)",
                self.case, self.wind
            ),
            None,
            true,
        )?;
        let (lo_n, hi_n) = (
            self.n.first().copied().unwrap_or(0) as f64,
            self.n.last().copied().unwrap_or(0) as f64,
        );
        let span = if hi_n > lo_n { hi_n - lo_n } else { 1000.0 };
        let (x0, x1) = (lo_n - 0.07 * span, hi_n + 0.07 * span);
        let dodge = 0.012 * span;
        for (o, area) in body.split_evenly((3, 1)).iter().enumerate() {
            let (name, unit) = AXES[o];
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("{name} ({unit})"),
                    (FONT, 19).into_font().style(FontStyle::Bold),
                )
                .margin(10)
                .margin_right(24)
                .x_label_area_size(46)
                .y_label_area_size(64)
                .build_cartesian_2d(x0..x1, 0f64..100f64)
                .map_err(e::<DB>)?;
            styled_mesh(
                &mut chart,
                "N (samples in the estimation record)",
                "fit (%)",
            )
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .draw()
            .map_err(e::<DB>)?;
            for (i, (series, colour)) in self.series.iter().zip(COLOURS).enumerate() {
                let offset = (i as f64 - 1.5) * dodge;
                let points: Vec<(f64, f64)> = self
                    .n
                    .iter()
                    .zip(&series[o])
                    .map(|(n, (m, _))| (*n as f64 + offset, *m))
                    .collect();
                let line = ShapeStyle::from(&colour).stroke_width(2);
                for piece in clip_band(&points, 0.0, 100.0) {
                    chart
                        .draw_series(LineSeries::new(piece, line))
                        .map_err(e::<DB>)?;
                }
                let inside = |y: f64| y.is_finite() && (0.0..=100.0).contains(&y);
                for (n, (m, sd)) in self.n.iter().zip(&series[o]) {
                    let x = *n as f64 + offset;
                    if inside(*m) {
                        chart
                            .draw_series(std::iter::once(Circle::new((x, *m), 4, colour.filled())))
                            .map_err(e::<DB>)?;
                    }
                    if !(m.is_finite() && sd.is_finite()) {
                        continue;
                    }
                    // A mean off the axis: an arrowhead on the edge it left
                    // by, and no ▲ ▼ of a spread whose centre is not drawn.
                    if !inside(*m) {
                        let (edge, head) = if *m < 0.0 {
                            (0.0, down(0, -6, colour.stroke_width(2)))
                        } else {
                            (100.0, up(0, 6, colour.stroke_width(2)))
                        };
                        chart
                            .draw_series(std::iter::once(EmptyElement::at((x, edge)) + head))
                            .map_err(e::<DB>)?;
                        continue;
                    }
                    if inside(m + sd) {
                        chart
                            .draw_series(std::iter::once(
                                EmptyElement::at((x, m + sd)) + up(0, 0, colour.filled()),
                            ))
                            .map_err(e::<DB>)?;
                    }
                    if inside(m - sd) {
                        chart
                            .draw_series(std::iter::once(
                                EmptyElement::at((x, m - sd)) + down(0, 0, colour.filled()),
                            ))
                            .map_err(e::<DB>)?;
                    }
                }
            }
        }
        for (k, line) in wrap(&self.caption(), 120).into_iter().enumerate() {
            let y = 8 + 24 * i32::try_from(k).unwrap_or(0);
            foot.draw(&Text::new(line, (24, y), (FONT, 15).into_font()))
                .map_err(e::<DB>)?;
        }
        Ok(())
    }
}

/// One case's track: name, wind, points (north, east), the share of
/// minutes whose mean yaw rate is below zero over the whole study, and the
/// steady turn's radius (mean speed over mean yaw rate of the record).
type Track = (String, f64, Vec<(f64, f64)>, f64, f64);

/// The track of run 0 of each case, integrated from the true velocities and
/// heading: the first minutes (where the turn and its zigzags show) above the
/// whole record.
pub struct TrackFigure {
    tracks: Vec<Track>,
    /// Samples of the zoomed first panel.
    first: usize,
}

const TRACK_PANEL: (u32, u32) = (620, 560);
const TRACK_FOOT: u32 = 110;

impl TrackFigure {
    fn new(report: &Report) -> TrackFigure {
        let h = 1.0;
        let tracks = report
            .margins
            .cases
            .iter()
            .map(|c| {
                // The ship's states are u, v, r (examples/models/ship.som).
                let t = &c.first;
                let (u, v) = (
                    t.states.first().map_or(&[][..], Vec::as_slice),
                    t.states.get(1).map_or(&[][..], Vec::as_slice),
                );
                let n = u.len().min(v.len()).max(1) as f64;
                let speed = u
                    .iter()
                    .zip(v)
                    .map(|(u, v)| (u * u + v * v).sqrt())
                    .sum::<f64>()
                    / n;
                let yaw = t
                    .states
                    .get(2)
                    .map_or(f64::NAN, |r| r.iter().sum::<f64>() / n);
                (
                    c.case.clone(),
                    c.wind,
                    track(u, v, &t.heading, h),
                    c.yaw_rate_blocks.negative_fraction(),
                    speed / yaw,
                )
            })
            .collect();
        TrackFigure { tracks, first: 300 }
    }

    fn caption(&self) -> String {
        let stops: Vec<String> = self
            .tracks
            .iter()
            .map(|(case, _, _, f, _)| format!("{:.1} % ({case} wind)", 100.0 * f))
            .collect();
        let radii: Vec<String> = self
            .tracks
            .iter()
            .map(|(case, _, _, _, r)| format!("{r:.0} m ({case} wind)"))
            .collect();
        format!(
            "The ship's position integrated from the TRUE surge u, sway v and heading ψ of Monte Carlo run 0 \
             (north: u cos ψ − v sin ψ, east: u sin ψ + v cos ψ, from the origin), equal scales on both axes. \
             The static offset holds a steady turn (radius: mean speed over mean yaw rate, {}) and the smoothed \
             pulses add the zigzags (top). A yaw pulse deep enough stops or reverses the turn for as long as it lasts, and the ship then \
             runs nearly straight: the excursions of the whole record (bottom). Over the whole study, the yaw rate \
             averaged over a minute is below zero in {} of the minutes.",
            radii.join(", "),
            stops.join(" and ")
        )
    }
}

/// One track panel with equal metres per pixel on both axes.
fn track_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    points: &[(f64, f64)],
) -> Result<(), String> {
    let (margin, xl, yl) = (16u32, 46u32, 70u32);
    let (_, area) = area.split_vertically(10);
    let area = area
        .titled(title, (FONT, 19).into_font().style(FontStyle::Bold))
        .map_err(e::<DB>)?;
    let (aw, ah) = area.dim_in_pixel();
    let pw = f64::from(aw.saturating_sub(2 * margin + yl).max(1));
    let ph = f64::from(ah.saturating_sub(2 * margin + xl).max(1));
    let (mut n0, mut n1, mut e0, mut e1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for (n, east) in points {
        n0 = n0.min(*n);
        n1 = n1.max(*n);
        e0 = e0.min(*east);
        e1 = e1.max(*east);
    }
    if !(n0.is_finite() && e0.is_finite()) {
        (n0, n1, e0, e1) = (-1.0, 1.0, -1.0, 1.0);
    }
    let scale = ((e1 - e0) / pw).max((n1 - n0) / ph).max(1e-9) * 1.1;
    let (ce, cn) = (0.5 * (e0 + e1), 0.5 * (n0 + n1));
    let (ex, ny) = (0.5 * scale * pw, 0.5 * scale * ph);
    let mut chart = ChartBuilder::on(&area)
        .margin(margin)
        .x_label_area_size(xl)
        .y_label_area_size(yl)
        .build_cartesian_2d((ce - ex)..(ce + ex), (cn - ny)..(cn + ny))
        .map_err(e::<DB>)?;
    styled_mesh(&mut chart, "east (m)", "north (m)")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .draw()
        .map_err(e::<DB>)?;
    let en: Vec<(f64, f64)> = points.iter().map(|(n, east)| (*east, *n)).collect();
    let style = ShapeStyle::from(&COLOURS[2]).stroke_width(1);
    chart
        .draw_series(LineSeries::new(en.iter().copied(), style))
        .map_err(e::<DB>)?;
    if let Some(start) = en.first() {
        chart
            .draw_series(std::iter::once(Circle::new(*start, 6, COLOURS[3].filled())))
            .map_err(e::<DB>)?
            .label("start")
            .legend(|(x, y)| Circle::new((x + 12, y), 5, COLOURS[3].filled()));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(e::<DB>)?;
    }
    Ok(())
}

impl Figure for TrackFigure {
    fn size(&self) -> (u32, u32) {
        let n = u32::try_from(self.tracks.len().max(1)).unwrap_or(1);
        (TRACK_PANEL.0 * n.max(2), 2 * TRACK_PANEL.1 + TRACK_FOOT)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(e::<DB>)?;
        let (body, foot) = root.split_vertically(2 * TRACK_PANEL.1);
        let columns = body.split_evenly((1, self.tracks.len().max(1)));
        for (column, (case, wind, points, _, _)) in columns.iter().zip(&self.tracks) {
            let (top, bottom) = column.split_vertically(TRACK_PANEL.1);
            let first = &points[..self.first.min(points.len())];
            track_panel(
                &top,
                &format!(
                    "{case} wind ({wind} m/s), run 0: the first {} s",
                    first.len()
                ),
                first,
            )?;
            track_panel(
                &bottom,
                &format!("{case} wind ({wind} m/s), run 0: all {} s", points.len()),
                points,
            )?;
        }
        let (w, _) = self.size();
        let chars = usize::try_from(w / 8).unwrap_or(120);
        for (k, line) in wrap(&self.caption(), chars).into_iter().enumerate() {
            let y = 8 + 22 * i32::try_from(k).unwrap_or(0);
            foot.draw(&Text::new(line, (24, y), (FONT, 15).into_font()))
                .map_err(e::<DB>)?;
        }
        Ok(())
    }
}

/// One validation run: the true outputs against the four models of run 0 at
/// the largest N.
pub struct ValidationFigure {
    case: String,
    wind: f64,
    n: usize,
    time: Vec<f64>,
    truth: Vec<Vec<f64>>,
    /// Per estimator: simulated outputs (empty when the estimate failed),
    /// fits, and whether the simulation diverged.
    models: Vec<(Vec<Vec<f64>>, [f64; 3], bool)>,
}

const VAL_HEAD: u32 = 90;

/// The validation figure's caption.
const VAL_CAPTION: &str = "The undisturbed validation record (zigzag-forward input with the thrust stepped) simulated \
                           from its first sample by each estimator's model of Monte Carlo run 0 at the largest N, drawn in \
                           the legend's order (where IV2 and IV3 coincide, IV3 covers IV2), the true outputs last, translucent \
                           over them; a curve that leaves the panel is cut at its edge.";
const VAL_PANEL: u32 = 290;

impl ValidationFigure {
    fn new(model: &dyn Model, report: &Report, case: usize, validation: &Experiment) -> Self {
        let cfg = &report.outcomes.config;
        let last = cfg.n.len().saturating_sub(1);
        let run0 = report
            .outcomes
            .outcomes
            .get(case)
            .and_then(|runs| runs.first())
            .and_then(|per_n| per_n.get(last));
        let models = (0..ESTIMATORS.len())
            .map(|m| match run0.and_then(|r| r.get(m)) {
                Some(outcome) => match &outcome.theta {
                    Some(theta) => {
                        let sim = simulate(model, theta, validation, Disturbances::None);
                        (sim.states, outcome.fit, sim.diverged)
                    }
                    None => (Vec::new(), outcome.fit, true),
                },
                None => (Vec::new(), [f64::NAN; 3], true),
            })
            .collect();
        ValidationFigure {
            case: cfg
                .cases
                .get(case)
                .map(|c| c.name.clone())
                .unwrap_or_default(),
            wind: cfg.cases.get(case).map_or(f64::NAN, |c| c.wind),
            n: cfg.n.get(last).copied().unwrap_or(0),
            time: (0..validation.len())
                .map(|k| k as f64 * validation.h)
                .collect(),
            truth: validation.states.clone(),
            models,
        }
    }
}

impl Figure for ValidationFigure {
    fn size(&self) -> (u32, u32) {
        // Room for every caption line, 22 px each, and a margin under the last.
        let lines = u32::try_from(wrap(VAL_CAPTION, 130).len()).unwrap_or(4);
        (WIDTH, VAL_HEAD + 3 * VAL_PANEL + 22 * lines + 24)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(e::<DB>)?;
        let (head, rest) = root.split_vertically(VAL_HEAD);
        let (body, foot) = rest.split_vertically(3 * VAL_PANEL);
        header(
            &head,
            &format!(
                "Validation: the models of run 0 at N = {}, {} wind (mean wind {} m/s north and east)",
                self.n, self.case, self.wind
            ),
            Some("true (undisturbed)"),
            false,
        )?;
        let (t0, t1) = match (self.time.first(), self.time.last()) {
            (Some(a), Some(b)) if b > a => (*a, *b),
            _ => (0.0, 1.0),
        };
        for (o, area) in body.split_evenly((3, 1)).iter().enumerate() {
            let (name, unit) = AXES[o];
            let truth: Vec<(f64, f64)> = self
                .time
                .iter()
                .copied()
                .zip(self.truth.get(o).cloned().unwrap_or_default())
                .collect();
            let sims: Vec<Vec<(f64, f64)>> = self
                .models
                .iter()
                .map(|(states, _, _)| {
                    self.time
                        .iter()
                        .copied()
                        .zip(states.get(o).cloned().unwrap_or_default())
                        .collect()
                })
                .collect();
            let all: Vec<(f64, f64)> = sims.iter().flatten().copied().collect();
            let (y0, y1) = y_range(&truth, &all);
            let fits: Vec<String> = ESTIMATORS
                .iter()
                .zip(&self.models)
                .map(|(est, (_, fit, diverged))| {
                    if fit[o].is_finite() {
                        format!("{est} {:.1}", fit[o])
                    } else if *diverged {
                        format!("{est} diverged")
                    } else {
                        format!("{est} -")
                    }
                })
                .collect();
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("{name} ({unit}); fit (%): {}", fits.join(", ")),
                    (FONT, 18).into_font().style(FontStyle::Bold),
                )
                .margin(10)
                .margin_right(24)
                .x_label_area_size(44)
                .y_label_area_size(76)
                .build_cartesian_2d(t0..t1, y0..y1)
                .map_err(e::<DB>)?;
            let y_desc = format!("{} ({unit})", name.rsplit(' ').next().unwrap_or(name));
            let decimals = tick_decimals(y1 - y0);
            styled_mesh(&mut chart, "time (s)", &y_desc)
                .x_label_formatter(&|x| format!("{x:.0}"))
                .y_label_formatter(&|y| tick(*y, decimals))
                .draw()
                .map_err(e::<DB>)?;
            // The models first, the truth last and translucent over them,
            // so that the best model's curve does not hide it.
            let truth_style = ShapeStyle::from(&BLACK.mix(0.35)).stroke_width(5);
            let sims_and_truth = sims
                .iter()
                .zip(COLOURS.map(|c| ShapeStyle::from(&c).stroke_width(2)))
                .chain(std::iter::once((&truth, truth_style)));
            for (points, style) in sims_and_truth {
                for piece in clip_band(points, y0, y1) {
                    for part in split_sharp(&piece, |p| chart.backend_coord(&p)) {
                        chart
                            .draw_series(LineSeries::new(part, style))
                            .map_err(e::<DB>)?;
                    }
                }
            }
        }
        for (k, line) in wrap(VAL_CAPTION, 130).into_iter().enumerate() {
            let y = 6 + 22 * i32::try_from(k).unwrap_or(0);
            foot.draw(&Text::new(line, (24, y), (FONT, 15).into_font()))
                .map_err(e::<DB>)?;
        }
        Ok(())
    }
}
