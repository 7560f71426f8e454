//! Plots of measured against simulated signals (plotters, no system fonts:
//! DejaVu Sans is compiled in and registered before drawing). The backend
//! follows the file's extension: `.png` a bitmap, anything else SVG. Any
//! figure implements [`Figure`]; [`clip_band`] cuts a polyline at the edge of
//! an axis's band.

use crate::files::create_output;
use crate::output::io_reason;
use plotters::chart::MeshStyle;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;

/// One panel: a measured signal and its simulation by one or more models,
/// over experiments drawn end to end on the time axis.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// The y-axis label.
    pub y_label: String,
    /// The experiments, in order, each on its own stretch of the time axis.
    pub segments: Vec<Segment>,
}

/// One experiment's stretch of a panel.
#[derive(Clone, Debug)]
pub struct Segment {
    /// The experiment's name, written at its start when there are several.
    pub name: String,
    /// Sample times on the panel's axis (already offset after earlier experiments).
    pub time: Vec<f64>,
    /// The measurement.
    pub measured: Vec<f64>,
    /// One simulation per model, in legend order (non-finite values after a
    /// divergence are not drawn).
    pub simulated: Vec<Vec<f64>>,
}

/// The colours of the models' lines, in order (the measurement is grey).
pub const MODEL_COLOURS: [RGBColor; 6] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Most experiment names written on a panel; with more, the separators stay
/// and the names are listed in the text output.
const MAX_SEGMENT_LABELS: usize = 12;

const WIDTH: u32 = 1000;
const PANEL_HEIGHT: u32 = 280;
/// Most points drawn per series; longer records keep each bucket's extremes.
const MAX_POINTS: usize = 4000;

/// Registers DejaVu Sans (regular and bold) as `sans-serif`, once: plotters
/// draws text only with registered fonts, for SVG too.
pub fn register_fonts() -> Result<(), String> {
    static FONTS: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    FONTS
        .get_or_init(|| {
            for (style, bytes) in [
                (FontStyle::Normal, dejavu::sans::regular()),
                (FontStyle::Bold, dejavu::sans::bold()),
            ] {
                plotters::style::register_font("sans-serif", style, bytes)
                    .map_err(|_| "the compiled-in DejaVu font is invalid".to_string())?;
            }
            Ok(())
        })
        .clone()
}

/// A figure that draws itself on any plotters backend.
pub trait Figure {
    /// Width and height in pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the whole figure on `root`.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Draws a figure into `path`: a bitmap for a `.png` name, SVG otherwise.
/// The file is created first by [`create_output`] (a symbolic link in the
/// way is refused, never followed); on an error no half-written file is
/// left behind.
pub fn save(path: &Path, figure: &impl Figure) -> Result<(), String> {
    register_fonts()?;
    create_output(path).map_err(|e| io_reason(&e))?;
    let size = figure.size();
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let result = if png {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        figure
            .draw(&root)
            .and_then(|()| root.present().map_err(|e| e.to_string()))
    } else {
        let root = SVGBackend::new(path, size).into_drawing_area();
        figure
            .draw(&root)
            .and_then(|()| root.present().map_err(|e| e.to_string()))
    };
    if result.is_err() {
        let _ = std::fs::remove_file(path);
    }
    result
}

/// Measured against simulated, one panel per signal, stacked; `models`
/// names the simulations in the legend.
struct Panels<'a>(&'a [Panel], &'a [String]);

impl Figure for Panels<'_> {
    fn size(&self) -> (u32, u32) {
        let height = u32::try_from(self.0.len().max(1))
            .unwrap_or(u32::MAX)
            .saturating_mul(PANEL_HEIGHT);
        (WIDTH, height)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        draw_on(root, self.0, self.1)
    }
}

/// Draws the panels, stacked vertically, into `path`; `models` names the
/// simulated lines. On an error no half-written file is left behind.
pub fn draw(path: &Path, panels: &[Panel], models: &[String]) -> Result<(), String> {
    save(path, &Panels(panels, models))
}

/// At most `max` points (at least 2): the smallest and largest value of each
/// bucket, in time order, so peaks survive.
pub fn decimate_to(time: &[f64], values: &[f64], max: usize) -> Vec<(f64, f64)> {
    let max = max.max(2);
    let points: Vec<(f64, f64)> = time
        .iter()
        .copied()
        .zip(values.iter().copied())
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .collect();
    if points.len() <= max {
        return points;
    }
    let bucket = points.len().div_ceil(max / 2);
    let mut out = Vec::with_capacity(max);
    for chunk in points.chunks(bucket) {
        let lo = chunk.iter().min_by(|a, b| a.1.total_cmp(&b.1));
        let hi = chunk.iter().max_by(|a, b| a.1.total_cmp(&b.1));
        if let (Some(lo), Some(hi)) = (lo, hi) {
            if lo.0 <= hi.0 {
                out.extend([*lo, *hi]);
            } else {
                out.extend([*hi, *lo]);
            }
        }
    }
    out
}

/// The pieces of a polyline inside `lo ≤ y ≤ hi`: segments that leave the
/// band are cut where they cross its edge, non-finite points break the line.
/// Pieces have at least two points.
pub fn clip_band(points: &[(f64, f64)], lo: f64, hi: f64) -> Vec<Vec<(f64, f64)>> {
    fn flush(piece: &mut Vec<(f64, f64)>, pieces: &mut Vec<Vec<(f64, f64)>>) {
        if piece.len() >= 2 {
            pieces.push(std::mem::take(piece));
        } else {
            piece.clear();
        }
    }
    let mut pieces = Vec::new();
    let mut piece: Vec<(f64, f64)> = Vec::new();
    for w in points.windows(2) {
        let (p, q) = (w[0], w[1]);
        if ![p.0, p.1, q.0, q.1].iter().all(|v| v.is_finite()) {
            flush(&mut piece, &mut pieces);
            continue;
        }
        let dy = q.1 - p.1;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        if dy == 0.0 {
            if p.1 < lo || p.1 > hi {
                flush(&mut piece, &mut pieces);
                continue;
            }
        } else {
            let (ta, tb) = ((lo - p.1) / dy, (hi - p.1) / dy);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
            if t0 > t1 {
                flush(&mut piece, &mut pieces);
                continue;
            }
        }
        let at = |t: f64| (p.0 + t * (q.0 - p.0), (p.1 + t * dy).clamp(lo, hi));
        if t0 > 0.0 || piece.is_empty() {
            flush(&mut piece, &mut pieces);
            piece.push(at(t0));
        }
        piece.push(at(t1));
        if t1 < 1.0 {
            flush(&mut piece, &mut pieces);
        }
    }
    flush(&mut piece, &mut pieces);
    pieces
}

/// The pieces of a polyline split at its sharp turns (more than 120° in
/// pixels, `to_pixel`): a thick line in the PNG backend joins segments with
/// unlimited miters, so a chattering simulation would draw spikes far across
/// the neighbouring panels; pieces that meet at a vertex without a join do not.
pub fn split_sharp(
    points: &[(f64, f64)],
    to_pixel: impl Fn((f64, f64)) -> (i32, i32),
) -> Vec<Vec<(f64, f64)>> {
    let mut pieces = Vec::new();
    let mut piece: Vec<(f64, f64)> = Vec::new();
    for &p in points {
        if let [.., a, b] = piece[..] {
            let (pa, pb, pc) = (to_pixel(a), to_pixel(b), to_pixel(p));
            let (u, v) = (
                (f64::from(pb.0 - pa.0), f64::from(pb.1 - pa.1)),
                (f64::from(pc.0 - pb.0), f64::from(pc.1 - pb.1)),
            );
            let (nu, nv) = (u.0.hypot(u.1), v.0.hypot(v.1));
            if nu > 0.0 && nv > 0.0 && (u.0 * v.0 + u.1 * v.1) / (nu * nv) < -0.5 {
                pieces.push(std::mem::replace(&mut piece, vec![b]));
            }
        }
        piece.push(p);
    }
    if piece.len() >= 2 {
        pieces.push(piece);
    }
    pieces
}

/// A tick label: `-0.0` reads `0`, as does any label that rounds to zero.
pub fn tick(y: f64, decimals: usize) -> String {
    let text = format!("{y:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        format!("{:.decimals$}", 0.0)
    } else {
        text
    }
}

/// Decimals enough to tell ticks apart on a range of width `span`.
pub fn tick_decimals(span: f64) -> usize {
    if !(span.is_finite() && span > 0.0) {
        return 1;
    }
    // About ten ticks a panel: one decimal more than the step's magnitude.
    let step = span / 10.0;
    (-step.log10().floor()).clamp(0.0, 6.0) as usize
}

/// The corner of a chart whose quarter holds the fewest points: where a
/// legend hides the least.
pub fn emptiest_corner(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let (xm, ym) = (x.0 + 0.7 * (x.1 - x.0), y.0 + 0.7 * (y.1 - y.0));
    let (xl, yl) = (x.0 + 0.3 * (x.1 - x.0), y.0 + 0.3 * (y.1 - y.0));
    let count = |fx: &dyn Fn(f64) -> bool, fy: &dyn Fn(f64) -> bool| {
        points.iter().filter(|p| fx(p.0) && fy(p.1)).count()
    };
    let corners = [
        (
            count(&|t| t >= xm, &|v| v >= ym),
            SeriesLabelPosition::UpperRight,
        ),
        (
            count(&|t| t <= xl, &|v| v >= ym),
            SeriesLabelPosition::UpperLeft,
        ),
        (
            count(&|t| t >= xm, &|v| v <= yl),
            SeriesLabelPosition::LowerRight,
        ),
        (
            count(&|t| t <= xl, &|v| v <= yl),
            SeriesLabelPosition::LowerLeft,
        ),
    ];
    corners
        .into_iter()
        .min_by_key(|(n, _)| *n)
        .map_or(SeriesLabelPosition::UpperRight, |(_, p)| p)
}

/// The mesh of every figure: the same fonts and grid, with these axis
/// descriptions; callers add label formatters and draw it.
pub fn styled_mesh<'a, 'b, DB: DrawingBackend>(
    chart: &'a mut ChartContext<'b, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    x_desc: &str,
    y_desc: &str,
) -> MeshStyle<'b, 'a, RangedCoordf64, RangedCoordf64, DB> {
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(BLACK.mix(0.04))
        .bold_line_style(BLACK.mix(0.12));
    mesh
}

/// The y range: the measurement's, widened to the simulation's unless the
/// simulation runs far off (then it leaves the panel rather than flatten the data).
pub fn y_range(measured: &[(f64, f64)], simulated: &[(f64, f64)]) -> (f64, f64) {
    let bounds = |pts: &[(f64, f64)]| {
        pts.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            })
    };
    let (mut lo, mut hi) = bounds(measured);
    if !lo.is_finite() {
        (lo, hi) = (-1.0, 1.0);
    }
    let span = (hi - lo).max(1e-9 * lo.abs().max(1.0));
    let (slo, shi) = bounds(simulated);
    if slo.is_finite() {
        lo = lo.min(slo.max(lo - span));
        hi = hi.max(shi.min(hi + span));
    }
    let pad = 0.05 * (hi - lo).max(1e-9);
    (lo - pad, hi + pad)
}

fn draw_on<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[Panel],
    models: &[String],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|err| err.to_string())?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (area, p) in areas.iter().zip(panels) {
        draw_panel(area, p, models)?;
    }
    Ok(())
}

/// One output: the measurement wide and grey, the simulations thin and
/// coloured on top (all stay visible), decimated to a budget of points.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    models: &[String],
) -> Result<(), String> {
    let e = |err: DrawingAreaErrorKind<DB::ErrorType>| err.to_string();
    let measured_style = ShapeStyle::from(&BLACK.mix(0.45)).stroke_width(3);
    let model_style =
        |m: usize| ShapeStyle::from(&MODEL_COLOURS[m % MODEL_COLOURS.len()]).stroke_width(1);
    let budget = MAX_POINTS / p.segments.len().max(1);
    let measured: Vec<Vec<(f64, f64)>> = p
        .segments
        .iter()
        .map(|s| decimate_to(&s.time, &s.measured, budget))
        .collect();
    let simulated: Vec<Vec<Vec<(f64, f64)>>> = p
        .segments
        .iter()
        .map(|s| {
            s.simulated
                .iter()
                .map(|v| decimate_to(&s.time, v, budget))
                .collect()
        })
        .collect();
    let first = p.segments.first().and_then(|s| s.time.first()).copied();
    let last = p.segments.last().and_then(|s| s.time.last()).copied();
    let (x0, x1) = match (first, last) {
        (Some(a), Some(b)) if b > a => (a, b),
        (Some(a), _) => (a, a + 1.0),
        _ => (0.0, 1.0),
    };
    let all_measured: Vec<(f64, f64)> = measured.iter().flatten().copied().collect();
    let all_simulated: Vec<(f64, f64)> = simulated.iter().flatten().flatten().copied().collect();
    let (y0, y1) = y_range(&all_measured, &all_simulated);
    let mut chart = ChartBuilder::on(area)
        .caption(
            &p.title,
            ("sans-serif", 22).into_font().style(FontStyle::Bold),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    let x_desc = if p.segments.len() > 1 {
        "time (s; experiments end to end)"
    } else {
        "time (s)"
    };
    let decimals = tick_decimals(y1 - y0);
    styled_mesh(&mut chart, x_desc, &p.y_label)
        .x_label_formatter(&|x| format!("{x}"))
        .y_label_formatter(&|y| tick(*y, decimals))
        .draw()
        .map_err(e)?;
    separators(&mut chart, p, (y0, y1)).map_err(e)?;
    let clip = |pts: &[(f64, f64)]| -> Vec<(f64, f64)> {
        pts.iter().map(|(t, v)| (*t, v.clamp(y0, y1))).collect()
    };
    let corner = emptiest_corner(
        &all_measured
            .iter()
            .chain(&all_simulated)
            .copied()
            .collect::<Vec<_>>(),
        (x0, x1),
        (y0, y1),
    );
    for (k, pts) in measured.iter().enumerate() {
        let pieces = split_sharp(&clip(pts), |p| chart.backend_coord(&p));
        for (i, piece) in pieces.into_iter().enumerate() {
            let series = chart
                .draw_series(LineSeries::new(piece, measured_style))
                .map_err(e)?;
            if k == 0 && i == 0 {
                series.label("measured").legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], measured_style)
                });
            }
        }
    }
    for (m, model) in models.iter().enumerate() {
        let style = model_style(m);
        for (k, seg) in simulated.iter().enumerate() {
            let Some(pts) = seg.get(m) else { continue };
            let series = chart
                .draw_series(LineSeries::new(clip(pts), style))
                .map_err(e)?;
            if k == 0 {
                series
                    .label(model.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
            }
        }
    }
    chart
        .configure_series_labels()
        .position(corner)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .draw()
        .map_err(e)?;
    Ok(())
}

/// Experiments after the first start at a dashed separator, named when
/// there is room.
fn separators<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    p: &Panel,
    (y0, y1): (f64, f64),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    if p.segments.len() > 1 {
        for (k, s) in p.segments.iter().enumerate() {
            let Some(&t) = s.time.first() else { continue };
            if k > 0 {
                chart.draw_series(DashedLineSeries::new(
                    [(t, y0), (t, y1)],
                    6,
                    4,
                    ShapeStyle::from(&BLACK.mix(0.5)).stroke_width(1),
                ))?;
            }
            if p.segments.len() <= MAX_SEGMENT_LABELS {
                chart.draw_series(std::iter::once(Text::new(
                    s.name.clone(),
                    (t, y1),
                    ("sans-serif", 13).into_font().color(&BLACK.mix(0.7)),
                )))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_extremes_and_order() {
        let n = 100_000;
        let time: Vec<f64> = (0..n).map(|k| k as f64).collect();
        let mut values = vec![0.0; n];
        values[12_345] = 7.0;
        values[54_321] = -3.0;
        let pts = decimate_to(&time, &values, MAX_POINTS);
        assert!(pts.len() <= MAX_POINTS);
        assert!(pts.windows(2).all(|w| w[0].0 <= w[1].0));
        assert!(pts.contains(&(12_345.0, 7.0)) && pts.contains(&(54_321.0, -3.0)));
    }

    #[test]
    fn clipping_cuts_at_the_band_edges() {
        let pts = [
            (0.0, 50.0),
            (1.0, 150.0),
            (2.0, 50.0),
            (3.0, 60.0),
            (4.0, f64::NAN),
            (5.0, 10.0),
            (6.0, 20.0),
        ];
        let pieces = clip_band(&pts, 0.0, 100.0);
        assert_eq!(
            pieces,
            vec![
                vec![(0.0, 50.0), (0.5, 100.0)],
                vec![(1.5, 100.0), (2.0, 50.0), (3.0, 60.0)],
                vec![(5.0, 10.0), (6.0, 20.0)],
            ]
        );
        // Entirely outside, or a single point: nothing to draw.
        assert!(clip_band(&[(0.0, -5.0), (1.0, -1.0)], 0.0, 100.0).is_empty());
        assert!(clip_band(&[(0.0, 5.0)], 0.0, 100.0).is_empty());
        // Crossing the whole band keeps the part inside.
        assert_eq!(
            clip_band(&[(0.0, -100.0), (2.0, 200.0)], 0.0, 100.0),
            vec![vec![(2.0 / 3.0, 0.0), (4.0 / 3.0, 100.0)]]
        );
    }

    #[test]
    fn a_runaway_simulation_does_not_flatten_the_measurement() {
        let measured = [(0.0, 0.0), (1.0, 1.0)];
        let (lo, hi) = y_range(&measured, &[(0.0, 0.5), (1.0, 1e9)]);
        assert!(hi < 2.5 && lo < 0.0, "{lo} {hi}");
        let (lo, hi) = y_range(&measured, &[(0.0, -0.5)]);
        assert!(lo < -0.5 && hi > 1.0, "{lo} {hi}");
    }

    #[test]
    fn svg_and_png_plots_render_text() {
        let dir = std::env::temp_dir().join(format!("leeway-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        let segment = |name: &str, from: f64| {
            let time: Vec<f64> = (0..200).map(|k| from + f64::from(k)).collect();
            Segment {
                name: name.to_string(),
                measured: time.iter().map(|t| (t / 20.0).sin()).collect(),
                simulated: vec![
                    time.iter().map(|t| 0.9 * (t / 20.0).sin()).collect(),
                    time.iter().map(|t| 0.8 * (t / 20.0).sin()).collect(),
                ],
                time,
            }
        };
        let panel = Panel {
            title: "u: fit 97.5 %".to_string(),
            y_label: "u (m/s)".to_string(),
            segments: vec![segment("run1", 0.0), segment("run2", 201.0)],
        };
        let models = ["est-a".to_string(), "est-b".to_string()];
        let svg = dir.join("p.svg");
        draw(&svg, &[panel.clone(), panel.clone()], &models).unwrap_or_else(|e| panic!("{e}"));
        let text = std::fs::read_to_string(&svg).unwrap_or_default();
        assert!(text.contains("<svg") && text.contains("</svg>"));
        for label in [
            "u: fit 97.5 %",
            "measured",
            "est-a",
            "est-b",
            "run2",
            "u (m/s)",
            "time (s; experiments end to end)",
        ] {
            assert!(text.contains(label), "{label} missing from the SVG");
        }
        let png = dir.join("p.png");
        draw(&png, &[panel], &models).unwrap_or_else(|e| panic!("{e}"));
        let bytes = std::fs::read(&png).unwrap_or_default();
        assert!(bytes.starts_with(b"\x89PNG"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
