//! The study's figures (plotters, bitmap backend, the bundled DejaVu Sans font):
//! `error-vs-time.png` (log-log error against time to the image, a curve per run: antiradiance
//! solid with circles, hierarchical radiosity dashed with triangles, progressive refinement
//! short-dashed with crosses, instant radiosity long-dashed with squares, the path tracer thick black; each method's equal-time comparison
//! with the path tracer stated, antiradiance's crossover marked; full image and indirect light)
//! and `convergence.png` (residual and error per iteration).

use super::Row;
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// DejaVu Sans (Bitstream Vera license, `DejaVuSans.LICENSE.txt` beside this file).
static FONT: &[u8] = include_bytes!("DejaVuSans.ttf");

pub(super) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Fails only for a malformed font; the bundled one is not.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        message: format!("plotting: {e}"),
    }
}

/// Piecewise log-log interpolation of `pts` (sorted by x) at `x`; None outside their range.
fn interp(pts: &[(f64, f64)], x: f64) -> Option<f64> {
    pts.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        (x >= x0 && x <= x1 && x1 > x0).then(|| {
            let t = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
            (y0.ln() + t * (y1.ln() - y0.ln())).exp()
        })
    })
}

/// The best error `method` reached at or before each time (its Pareto frontier).
fn frontier(rows: &[&Row], method: &str, err: impl Fn(&Row) -> Option<f64>) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.method == method)
        .filter_map(|r| err(r).map(|e| (r.total_ms(), e)))
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.1.is_finite())
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::INFINITY;
    pts.into_iter()
        .filter(|p| {
            let keep = p.1 < best;
            best = best.min(p.1);
            keep
        })
        .collect()
}

/// How the path tracer and antiradiance (or another method, [`crossover_for`]) compare at equal
/// time; the variants name antiradiance, [`Crossover::phrase`] any method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Crossover {
    /// Antiradiance is more accurate before this time (ms), the path tracer from then on.
    At(f64),
    /// The path tracer is at least as accurate at every time both were measured.
    PathTracerAhead,
    /// Antiradiance is more accurate at every time both were measured.
    AntiradianceAhead,
    /// Their measured times do not overlap (or a method is missing).
    NoOverlap,
}

impl std::fmt::Display for Crossover {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Crossover::At(ms) => write!(f, "equal-time crossover at {:.3} s", ms / 1e3),
            Crossover::PathTracerAhead => {
                write!(f, "path tracer more accurate at every shared time")
            }
            Crossover::AntiradianceAhead => {
                write!(f, "antiradiance more accurate at every shared time")
            }
            Crossover::NoOverlap => write!(f, "no overlap of measured times"),
        }
    }
}

impl Crossover {
    /// The comparison in words for `method` (e.g. `hierarchical-radiosity`).
    pub fn phrase(&self, method: &str) -> String {
        match self {
            Crossover::At(ms) => format!(
                "{method} ahead until {:.3} s, the path tracer after",
                ms / 1e3
            ),
            Crossover::PathTracerAhead => {
                format!("path tracer ahead of {method} at every shared time")
            }
            Crossover::AntiradianceAhead => {
                format!("{method} ahead of the path tracer at every shared time")
            }
            Crossover::NoOverlap => format!("{method}: no overlap with the path tracer's times"),
        }
    }
}

/// The equal-time comparison: over the times both methods were measured, where the path
/// tracer's error (log-log interpolation between its runs) drops to the best error antiradiance
/// reached by then (its Pareto frontier).
pub fn crossover(rows: &[Row], err: impl Fn(&Row) -> Option<f64> + Copy) -> Crossover {
    crossover_for(rows, "antiradiance", err)
}

/// [`crossover`] for `method`'s runs (a [`Row::method`] spelling).
pub fn crossover_for(
    rows: &[Row],
    method: &str,
    err: impl Fn(&Row) -> Option<f64> + Copy,
) -> Crossover {
    let all: Vec<&Row> = rows.iter().collect();
    let front = frontier(&all, method, err);
    let mut pt: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.method == "pathtracer")
        .filter_map(|r| err(r).map(|e| (r.total_ms(), e)))
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.1.is_finite())
        .collect();
    pt.sort_by(|a, b| a.0.total_cmp(&b.0));
    if pt.len() < 2 || front.is_empty() {
        return Crossover::NoOverlap;
    }
    let (t0, t1) = (pt[0].0.max(front[0].0), pt[pt.len() - 1].0);
    if t0 >= t1 {
        return Crossover::NoOverlap;
    }
    let best_at = |t: f64| front.iter().take_while(|p| p.0 <= t).last().map(|p| p.1);
    // Scan the shared time range finely (log-spaced).
    let n = 400;
    let ahead: Vec<(f64, bool)> = (0..=n)
        .map(|i| t0 * (t1 / t0).powf(i as f64 / n as f64))
        .filter_map(|t| Some((t, interp(&pt, t)? <= best_at(t)?)))
        .collect();
    match (ahead.first(), ahead.iter().find(|a| a.1)) {
        (None, _) => Crossover::NoOverlap,
        (_, None) => Crossover::AntiradianceAhead,
        (Some(first), Some(_)) if first.1 => Crossover::PathTracerAhead,
        (_, Some(a)) => Crossover::At(a.0),
    }
}

fn series_of(rows: &[Row]) -> Vec<(String, Vec<&Row>)> {
    let mut out: Vec<(String, Vec<&Row>)> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|(l, _)| *l == r.label) {
            Some((_, v)) => v.push(r),
            None => out.push((r.label.clone(), vec![r])),
        }
    }
    out
}

fn log_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0f64);
    for v in vals.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.1, 1.0);
    }
    (lo / 1.5, hi * 1.5)
}

/// Three significant digits, without float noise (log-axis tick labels).
fn tick(v: &f64) -> String {
    if *v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

type Panel<'a> = (&'a str, &'a dyn Fn(&Row) -> Option<f64>);
/// A convergence panel: title, y label, the figure per row, and whether its antiradiance rows
/// are only those of the `base` and `scheme` families (the baselines' always show).
type ConvergencePanel<'a> = (&'a str, &'a str, &'a dyn Fn(&Row) -> Option<f64>, bool);

/// How a method's curves are drawn: dash length and gap (0: solid), and the point marker.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Style {
    Solid,
    Dashed,
    Dotted,
    /// Instant radiosity: long dashes with squares, one point per VPL count.
    LongDashed,
}

fn style_of(method: &str) -> Style {
    match method {
        "hierarchical-radiosity" => Style::Dashed,
        "progressive-radiosity" => Style::Dotted,
        "instant-radiosity" | "image-based-radiosity" => Style::LongDashed,
        _ => Style::Solid,
    }
}

/// Draws one curve of `style` with its legend entry and markers.
fn draw_curve<DB: DrawingBackend, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    pts: Vec<(f64, f64)>,
    label: &str,
    style: Style,
    line: ShapeStyle,
    path: &Path,
) -> Result<()>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let dash = match style {
        Style::Solid => None,
        Style::Dashed => Some((10, 6)),
        Style::Dotted => Some((3, 4)),
        Style::LongDashed => Some((18, 5)),
    };
    let anno = match dash {
        None => chart
            .draw_series(LineSeries::new(pts.clone(), line))
            .map_err(|e| err(path, e))?,
        Some((d, g)) => chart
            .draw_series(DashedLineSeries::new(pts.clone(), d, g, line))
            .map_err(|e| err(path, e))?,
    };
    anno.label(label.to_string()).legend(move |(x, y)| {
        let (d, g) = dash.unwrap_or((18, 0));
        plotters::element::DashedPathElement::new(vec![(x, y), (x + 18, y)], d, g, line)
    });
    let color = line.color;
    match style {
        Style::Solid => chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled()))),
        Style::Dashed => chart.draw_series(
            pts.iter()
                .map(|&p| TriangleMarker::new(p, 4, color.filled())),
        ),
        Style::Dotted => {
            chart.draw_series(pts.iter().map(|&p| Cross::new(p, 4, color.stroke_width(2))))
        }
        Style::LongDashed => chart
            .draw_series(pts.iter().map(|&p| {
                EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], color.filled())
            })),
    }
    .map_err(|e| err(path, e))?;
    Ok(())
}

/// One color per curve label, the same in every panel and plot.
fn color_of(rows: &[Row], label: &str) -> RGBAColor {
    let i = series_of(rows)
        .iter()
        .position(|(l, _)| l == label)
        .unwrap_or(0);
    if rows
        .iter()
        .any(|r| r.label == label && r.method == "pathtracer")
    {
        BLACK.to_rgba()
    } else {
        Palette99::pick(i).to_rgba()
    }
}

/// Draws `error-vs-time.png`; returns the comparison for the full image's relative RMSE.
pub fn error_vs_time(rows: &[Row], path: &Path) -> Result<Crossover> {
    register_font();
    let full = |r: &Row| Some(r.full.rel_rmse);
    let indirect = |r: &Row| r.indirect.map(|m| m.rel_rmse);
    let panels: Vec<Panel> = if rows.iter().any(|r| r.indirect.is_some()) {
        vec![("full image", &full), ("indirect light only", &indirect)]
    } else {
        vec![("full image", &full)]
    };
    let root = BitMapBackend::new(path, (800 * panels.len() as u32, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let areas = root.split_evenly((1, panels.len()));
    let series = series_of(rows);
    let mut full_cross = Crossover::NoOverlap;
    for (area, (title, f)) in areas.iter().zip(&panels) {
        let (x0, x1) = log_range(rows.iter().map(|r| r.total_ms() / 1e3));
        let (y0, y1) = log_range(rows.iter().filter_map(f));
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("relative RMSE vs time, {title}"),
                ("sans-serif", 22),
            )
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| err(path, e))?;
        chart
            .configure_mesh()
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .x_desc("seconds to the image from scratch (linking + setup + iterations + frame)")
            .y_desc("relative RMSE")
            .draw()
            .map_err(|e| err(path, e))?;
        for (label, rs) in series.iter() {
            let is_pt = rs[0].method == "pathtracer";
            let color = color_of(rows, label);
            let line = color.stroke_width(if is_pt { 3 } else { 2 });
            let mut pts: Vec<(f64, f64)> = rs
                .iter()
                .filter_map(|r| f(r).map(|e| (r.total_ms() / 1e3, e)))
                .filter(|p| p.1 > 0.0 && p.1.is_finite())
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            draw_curve(&mut chart, pts, label, style_of(rs[0].method), line, path)?;
        }
        let cross = crossover(rows, *f);
        if *title == "full image" {
            full_cross = cross;
        }
        if let Crossover::At(t) = cross {
            let s = t / 1e3;
            chart
                .draw_series(LineSeries::new(vec![(s, y0), (s, y1)], RED.stroke_width(1)))
                .map_err(|e| err(path, e))?;
        }
        // One line per method measured: its equal-time comparison with the path tracer.
        let methods: Vec<&str> = crate::settings::Method::ALL
            .iter()
            .map(|m| m.as_str())
            .filter(|m| rows.iter().any(|r| r.method == *m))
            .collect();
        for (i, m) in methods.iter().enumerate() {
            let note = if *m == "antiradiance" && methods.len() == 1 {
                cross.to_string()
            } else {
                crossover_for(rows, m, *f).phrase(m)
            };
            chart
                .draw_series(std::iter::once(Text::new(
                    note,
                    (x0 * (x1 / x0).powf(0.3), y1 / 1.25f64.powi(1 + i as i32)),
                    ("sans-serif", 15).into_font().color(&RED),
                )))
                .map_err(|e| err(path, e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::LowerLeft)
            .draw()
            .map_err(|e| err(path, e))?;
    }
    root.present().map_err(|e| err(path, e))?;
    Ok(full_cross)
}

/// Draws `convergence.png`: residual per iteration for the scene's settings in both schemes,
/// and the full image's relative RMSE per iteration for every antiradiance run.
pub fn convergence(rows: &[Row], path: &Path) -> Result<()> {
    register_font();
    let root = BitMapBackend::new(path, (1600, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let areas = root.split_evenly((1, 2));
    let ar: Vec<Row> = rows
        .iter()
        // Instant and image-based radiosity do not iterate: on the error-against-time plot only.
        .filter(|r| {
            !matches!(
                r.method,
                "pathtracer" | "instant-radiosity" | "image-based-radiosity"
            )
        })
        .cloned()
        .collect();
    let kmax = ar
        .iter()
        .filter_map(|r| r.iterations)
        .max()
        .unwrap_or(1)
        .max(2) as f64;
    let panels: [ConvergencePanel; 2] = [
        (
            "residual per iteration (scene settings, both schemes; baselines)",
            "change of I_ex (progressive refinement: unshot power), relative",
            &|r: &Row| r.residual,
            true,
        ),
        (
            "error per iteration",
            "relative RMSE (full image)",
            &|r: &Row| Some(r.full.rel_rmse),
            false,
        ),
    ];
    for (area, (title, ydesc, f, schemes_only)) in areas.iter().zip(panels) {
        let keep = |r: &&Row| {
            !schemes_only
                || r.method != "antiradiance"
                || r.family == "base"
                || r.family == "scheme"
        };
        let (y0, y1) = log_range(ar.iter().filter(keep).filter_map(f));
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(0.5..kmax + 0.5, (y0..y1).log_scale())
            .map_err(|e| err(path, e))?;
        chart
            .configure_mesh()
            .x_labels(kmax as usize)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&tick)
            .x_desc("iteration")
            .y_desc(ydesc)
            .draw()
            .map_err(|e| err(path, e))?;
        let kept: Vec<Row> = ar.iter().filter(keep).cloned().collect();
        for (label, rs) in series_of(&kept) {
            let color = color_of(rows, &label);
            let pts: Vec<(f64, f64)> = rs
                .iter()
                .filter_map(|r| Some((r.iterations? as f64, f(r)?)))
                .filter(|p| p.1 > 0.0 && p.1.is_finite())
                .collect();
            let style = style_of(rs[0].method);
            draw_curve(&mut chart, pts, &label, style, color.stroke_width(2), path)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| err(path, e))?;
    }
    root.present().map_err(|e| err(path, e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_have_three_significant_digits() {
        assert_eq!(tick(&0.30000000000000004), "0.300");
        assert_eq!(tick(&2.0), "2.00");
        assert_eq!(tick(&150.0), "150");
        assert_eq!(tick(&0.001234), "0.00123");
    }

    fn row(method: &'static str, ms: f64, e: f64) -> Row {
        let m = crate::metrics::Metrics {
            rel_rmse: e,
            mare: e,
            flip: e,
        };
        Row {
            method,
            family: "x".into(),
            label: method.into(),
            bins: None,
            element_size: None,
            scheme: None,
            precision: None,
            iterations: None,
            spp: None,
            elements: None,
            links: None,
            linking_ms: 0.0,
            setup_ms: 0.0,
            frame_ms: ms,
            residual: None,
            full: m,
            indirect: None,
            fallbacks: Vec::new(),
            rays_per_link: None,
            subdivision: None,
            shots: None,
            vpl_paths: None,
            vpls: None,
            cube: None,
        }
    }

    #[test]
    fn crossover_cases() {
        let e = |r: &Row| Some(r.full.rel_rmse);
        // Path tracer error ∝ t^-1/2 from 1 at 10 ms; antiradiance flat at 0.1 from 20 ms.
        let pt = |k: f64| row("pathtracer", 10.0 * k, 1.0 / k.sqrt());
        let mut rows = vec![pt(1.0), pt(10.0), pt(100.0), pt(1000.0)];
        rows.push(row("antiradiance", 20.0, 0.1));
        match crossover(&rows, e) {
            Crossover::At(t) => assert!((t / 1000.0 - 1.0).abs() < 0.05, "{t}"),
            c => panic!("{c:?}"),
        }
        rows.pop();
        rows.push(row("antiradiance", 20.0, 0.001));
        assert_eq!(crossover(&rows, e), Crossover::AntiradianceAhead);
        rows.pop();
        rows.push(row("antiradiance", 20.0, 5.0));
        assert_eq!(crossover(&rows, e), Crossover::PathTracerAhead);
        rows.pop();
        rows.push(row("antiradiance", 1e6, 0.1));
        assert_eq!(crossover(&rows, e), Crossover::NoOverlap);
    }

    #[test]
    fn log_log_interpolation() {
        let pts = [(1.0, 1.0), (100.0, 0.01)];
        assert!((interp(&pts, 10.0).unwrap() - 0.1).abs() < 1e-12);
        assert!(interp(&pts, 1000.0).is_none());
    }
}
