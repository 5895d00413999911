//! The figure of a simulated run as SVG text (what `lagrange simulate --plot`
//! writes, and what the Python package shows for a run).
//!
//! Enter at [`svg`] with a [`PlotData`], or gather one as a run streams with
//! [`PlotKeeper`]. The figure has a title and subtitle on top and these panels:
//! - the coordinates against time (upper left; the whole left column when nothing is conserved);
//! - the drift of each quantity the derivation says is conserved, against time (lower left, sharing the time
//!   axis), when there is one;
//! - the paths of the particles in the plane, (x, y) at equal scale, when every point of the model is a particle
//!   with a 2-D position (upper right);
//! - phase portraits q' against q (right column, below the paths; one per coordinate when there are at most
//!   three, or two side by side below the paths, else of the first coordinate only).
//!
//! Angles (see [`crate::angles`]) are drawn wrapped to (−π, π], their lines broken where they wrap, so that a
//! pendulum that goes over the top stays on the axis instead of running off to 68.
//!
//! Legends sit in strips beside the plot areas, never on a curve.
//!
//! Nothing here trusts the data: non-finite samples are skipped (a line breaks at them), constant series get a
//! nonzero axis range, at most [`MAX_SERIES`] series are drawn per panel, and long runs are decimated to about
//! [`MAX_POINTS`] points per curve by keeping the extremes of each bucket, so spikes survive and files stay small.

mod keeper;
mod section;

pub use keeper::PlotKeeper;
pub use section::{section_subtitle, section_svg, SectionPlot, SectionSet};

use crate::DrawError;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::error::Error;
use std::f64::consts::{PI, TAU};

/// A named sequence of samples, one per entry of [`PlotData::time`].
pub struct Series {
    /// The name shown in legends and axis labels, such as `a` or `a'`.
    pub name: String,
    /// The samples; non-finite ones are skipped when drawing.
    pub values: Vec<f64>,
    /// Whether the samples are an angle, drawn wrapped to (−π, π].
    pub angle: bool,
}

/// The path of one particle in the plane, one (x, y) per entry of [`PlotData::time`].
pub struct Path {
    /// The particle's name, such as `particle 1`.
    pub name: String,
    /// Its x positions.
    pub x: Vec<f64>,
    /// Its y positions.
    pub y: Vec<f64>,
}

/// Everything [`svg`] draws: a run of a model sampled at common times.
pub struct PlotData {
    /// The figure's title, normally the model name.
    pub title: String,
    /// The line under the title, such as `dop853, rtol 1e-10, 12345 steps`.
    pub subtitle: String,
    /// The sample times.
    pub time: Vec<f64>,
    /// The generalized coordinates q_i(t).
    pub coordinates: Vec<Series>,
    /// The generalized velocities q_i'(t), in the order of [`PlotData::coordinates`].
    pub velocities: Vec<Series>,
    /// Conserved quantities along the run, as absolute values; the figure shows their drift from the first sample.
    /// None: no drift panel.
    pub invariants: Vec<Series>,
    /// The particles' paths in the plane; none: no path panel.
    pub paths: Vec<Path>,
}

/// Most curves drawn in one panel; further series are left out and the legend says so.
const MAX_SERIES: usize = 8;
/// About the most points kept per curve; enough for a smooth line at 1280 px, small enough for a light file.
const MAX_POINTS: usize = 4000;

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 800;
/// Drawing happens at `SCALE` times the figure's size, and the SVG's `viewBox` shrinks it back: plotters rounds
/// coordinates to whole pixels, which would make curves visibly stair-stepped when a slide is zoomed.
pub(crate) const SCALE: u32 = 4;
/// Phase portraits side by side only up to this many coordinates; beyond, the first coordinate alone.
const MAX_PHASE: usize = 3;
pub(crate) const FONT: &str = "sans-serif";

/// Tableau 10 without its yellow, which is faint on white.
const PALETTE: [RGBColor; MAX_SERIES] = [
    RGBColor(0x4e, 0x79, 0xa7),
    RGBColor(0xf2, 0x8e, 0x2b),
    RGBColor(0xe1, 0x57, 0x59),
    RGBColor(0x76, 0xb7, 0xb2),
    RGBColor(0x59, 0xa1, 0x4f),
    RGBColor(0xb0, 0x7a, 0xa1),
    RGBColor(0xff, 0x9d, 0xa7),
    RGBColor(0x9c, 0x75, 0x5f),
];
const INK: RGBColor = RGBColor(0x22, 0x22, 0x22);
const MUTED: RGBColor = RGBColor(0x66, 0x66, 0x66);
const GRID: RGBColor = RGBColor(0xe4, 0xe4, 0xe4);
const AXIS: RGBColor = RGBColor(0x99, 0x99, 0x99);

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<Coord, Coord>>;
type DrawResult = Result<(), Box<dyn Error>>;

/// A length in figure pixels, as drawn at [`SCALE`].
pub(crate) fn px(len: u32) -> u32 {
    len * SCALE
}

/// Like [`px`], for positions.
pub(crate) fn pos(len: i32) -> i32 {
    len * SCALE as i32
}

/// A text style of `size` figure pixels.
pub(crate) fn text_style(size: u32, color: &'static RGBColor, anchor: (HPos, VPos)) -> TextStyle<'static> {
    TextStyle::from((FONT, px(size)).into_font()).color(color).pos(Pos::new(anchor.0, anchor.1))
}

fn bold_style(size: u32, anchor: (HPos, VPos)) -> TextStyle<'static> {
    TextStyle::from((FONT, px(size)).into_font().style(FontStyle::Bold)).color(&INK).pos(Pos::new(anchor.0, anchor.1))
}

/// The whole figure as SVG text.
pub fn svg(data: &PlotData) -> Result<String, DrawError> {
    Ok(render(data)?)
}

fn render(data: &PlotData) -> Result<String, Box<dyn Error>> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (px(WIDTH), px(HEIGHT))).into_drawing_area();
        root.fill(&WHITE)?;
        let (header, body) = root.split_vertically(px(96));
        draw_header(&header, data)?;
        let body = body.margin(0, px(10), px(10), px(14));
        // The paths of particles want room of their own: the time panels give some of theirs.
        let left_share = if data.paths.is_empty() { 60 } else { 55 };
        let (left, right) = body.split_horizontally(px(WIDTH * left_share / 100));
        // Both left panels plot against time: equal room for the y labels aligns their time axes.
        let time = Axis::of(&data.time, 8);
        let values = coordinate_axis(data);
        let drifts: Vec<Drift> =
            data.invariants.iter().take(MAX_SERIES).map(|series| Drift::of(&series.values)).collect();
        let scale = DriftScale::new(&drifts);
        let coordinate_label = |value: &f64| format_tick(*value, values.step);
        let drift_label = |value: &f64| scale.label(*value);
        let mut y_area = label_width(&root, &values.ticks, &coordinate_label)?;
        if drifts.is_empty() {
            draw_coordinates(&left, data, &time, &values, y_area)?;
        } else {
            y_area = y_area.max(label_width(&root, &scale.axis.ticks, &drift_label)?);
            let (upper, lower) = left.split_vertically(body.dim_in_pixel().1 / 2);
            draw_coordinates(&upper, data, &time, &values, y_area)?;
            draw_drift(&lower, data, &time, &drifts, &scale, y_area)?;
        }
        let right = right.margin(0, 0, px(24), 0);
        if data.paths.is_empty() {
            draw_phase(&right, data, false)?;
        } else {
            let (upper, lower) = right.split_vertically(right.dim_in_pixel().1 * 55 / 100);
            draw_paths(&upper, data)?;
            draw_phase(&lower, data, true)?;
        }
        root.present()?;
    }
    let big = format!("width=\"{}\" height=\"{}\"", px(WIDTH), px(HEIGHT));
    Ok(svg.replacen(&big, &format!("width=\"{WIDTH}\" height=\"{HEIGHT}\""), 1))
}

fn draw_header(area: &Area, data: &PlotData) -> DrawResult {
    let center = area.dim_in_pixel().0 as i32 / 2;
    area.draw_text(&shorten(&data.title, 70), &bold_style(38, (HPos::Center, VPos::Top)), (center, pos(16)))?;
    area.draw_text(
        &shorten(&data.subtitle, 120),
        &text_style(22, &MUTED, (HPos::Center, VPos::Top)),
        (center, pos(60)),
    )?;
    Ok(())
}

/// The value axis of the coordinates panel, over the coordinates it shows.
fn coordinate_axis(data: &PlotData) -> Axis {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for series in data.coordinates.iter().take(MAX_SERIES) {
        let (a, b) = finite_range(&drawn(series));
        lo = lo.min(a);
        hi = hi.max(b);
    }
    Axis::new(lo, hi, 6)
}

fn draw_coordinates(area: &Area, data: &PlotData, time: &Axis, values: &Axis, y_area: u32) -> DrawResult {
    let shown = &data.coordinates[..data.coordinates.len().min(MAX_SERIES)];
    let (chart_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0 - px(150));
    if shown.is_empty() || !data.time.iter().any(|t| t.is_finite()) {
        return draw_message(&chart_area, "Coordinates", "no samples");
    }
    let y_label = |value: &f64| format_tick(*value, values.step);
    let caption = if shown.iter().any(wraps) { "Coordinates (angles wrapped to (−π, π])" } else { "Coordinates" };
    let mut chart = build_chart(&chart_area, caption, time, values, &y_label, y_area)?;
    configure_mesh(&mut chart, time, "t", "q", &y_label)?;
    for (idx, series) in shown.iter().enumerate() {
        draw_curves(&mut chart, &time_segments(&data.time, series), PALETTE[idx], 2)?;
    }
    let entries: Vec<(String, RGBColor)> =
        shown.iter().enumerate().map(|(idx, series)| (series.name.clone(), PALETTE[idx])).collect();
    draw_legend(&legend_area, &entries, data.coordinates.len())?;
    Ok(())
}

fn draw_drift(
    area: &Area,
    data: &PlotData,
    time: &Axis,
    drifts: &[Drift],
    scale: &DriftScale,
    y_area: u32,
) -> DrawResult {
    let shown = &data.invariants[..drifts.len()];
    let (chart_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0 - px(150));
    let n_relative = drifts.iter().filter(|drift| drift.relative).count();
    let y_desc = if n_relative == drifts.len() {
        "relative drift (I − I₀)/|I₀|"
    } else if n_relative == 0 {
        "absolute drift I − I₀"
    } else {
        "drift (I − I₀)/|I₀| or I − I₀"
    };
    let caption = if scale.threshold.is_some() {
        "Drift of conserved quantities (symlog scale)"
    } else {
        "Drift of conserved quantities"
    };
    let y_label = |value: &f64| scale.label(*value);
    let mut chart = build_chart(&chart_area, caption, time, &scale.axis, &y_label, y_area)?;
    configure_mesh(&mut chart, time, "t", y_desc, &y_label)?;
    let zero = [(time.lo, 0.0), (time.hi, 0.0)];
    chart.draw_series(LineSeries::new(zero, AXIS.stroke_width(px(1))))?;
    for (idx, drift) in drifts.iter().enumerate() {
        let mapped =
            Series { name: String::new(), values: drift.values.iter().map(|&v| scale.map(v)).collect(), angle: false };
        draw_curves(&mut chart, &time_segments(&data.time, &mapped), PALETTE[idx], 2)?;
    }
    let entries: Vec<(String, RGBColor)> = shown
        .iter()
        .zip(drifts)
        .enumerate()
        .map(|(idx, (series, drift))| {
            let name =
                if drift.relative || n_relative == 0 { series.name.clone() } else { format!("{} (abs.)", series.name) };
            (name, PALETTE[idx])
        })
        .collect();
    draw_legend(&legend_area, &entries, data.invariants.len())?;
    Ok(())
}

/// The phase portraits, stacked in a column (at most [`MAX_PHASE`]), or side by side in a row when `in_row` (at
/// most two); beyond, of the first coordinate only.
fn draw_phase(area: &Area, data: &PlotData, in_row: bool) -> DrawResult {
    let n_coords = data.coordinates.len().min(data.velocities.len());
    // Side by side, three would be too narrow to read.
    let most = if in_row { MAX_PHASE - 1 } else { MAX_PHASE };
    let n_panels = if n_coords <= most { n_coords } else { 1 };
    if n_panels == 0 {
        return draw_message(area, "Phase portrait", "no coordinates");
    }
    let panels = area.split_evenly(if in_row { (1, n_panels) } else { (n_panels, 1) });
    let crowded = in_row && n_panels > 1;
    for (coord_idx, panel) in panels.iter().enumerate() {
        let q = &data.coordinates[coord_idx];
        let v = &data.velocities[coord_idx];
        let (q_name, v_name) = (shorten(&q.name, 16), shorten(&v.name, 16));
        let v_name = if v_name.is_empty() { format!("{q_name}'") } else { v_name };
        let caption = if data.coordinates.len() > n_panels {
            format!("Phase portrait of {q_name} (first of {})", data.coordinates.len())
        } else if crowded {
            format!("Phase of {q_name}")
        } else {
            format!("Phase portrait of {q_name}")
        };
        let q_desc = if wraps(q) { format!("{q_name} (wrapped)") } else { q_name.clone() };
        let (x_lo, x_hi) = finite_range(&drawn(q));
        let (y_lo, y_hi) = finite_range(&v.values);
        let x_axis = Axis::new(x_lo, x_hi, if crowded { 4 } else { 5 });
        let y_axis = Axis::new(y_lo, y_hi, if n_panels == 3 && !in_row { 4 } else { 5 });
        let y_label = |value: &f64| format_tick(*value, y_axis.step);
        let mut chart = build_chart(panel, &caption, &x_axis, &y_axis, &y_label, 0)?;
        configure_mesh(&mut chart, &x_axis, &q_desc, &v_name, &y_label)?;
        let segments = phase_segments(q, v);
        draw_curves(&mut chart, &segments, PALETTE[coord_idx].mix(0.85), 1)?;
        if let Some(&start) = segments.first().and_then(|segment| segment.first()) {
            // The label on the side of the marker away from the frame, so that it stays inside the plot.
            let (right, top) = (
                (start.0 - x_axis.lo) / (x_axis.hi - x_axis.lo) > 0.8,
                (start.1 - y_axis.lo) / (y_axis.hi - y_axis.lo) > 0.85,
            );
            let (h, dx) = if right { (HPos::Right, -7) } else { (HPos::Left, 7) };
            let (v, dy) = if top { (VPos::Top, 5) } else { (VPos::Bottom, -5) };
            let marker = EmptyElement::at(start)
                + Circle::new((0, 0), px(5), INK.filled())
                + Text::new("start", (pos(dx), pos(dy)), text_style(16, &INK, (h, v)));
            chart.draw_series(std::iter::once(marker))?;
        }
    }
    Ok(())
}

/// The particles' paths in the plane at equal scale on both axes, each in its colour, each start marked; the
/// legend in a strip to the right.
fn draw_paths(area: &Area, data: &PlotData) -> DrawResult {
    let shown = &data.paths[..data.paths.len().min(MAX_SERIES)];
    let (chart_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0 - px(120));
    let caption = if shown.len() == 1 { "Path in the plane" } else { "Paths in the plane" };
    let plot = chart_area.titled(caption, bold_style(23, (HPos::Center, VPos::Top)))?;
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for path in shown {
        let ((a, b), (c, d)) = (finite_range(&path.x), finite_range(&path.y));
        (x_lo, x_hi, y_lo, y_hi) = (x_lo.min(a), x_hi.max(b), y_lo.min(c), y_hi.max(d));
    }
    let (width, height) = plot.dim_in_pixel();
    // The y labels' width sets the plot's width, which sets the y range: twice settles it.
    let mut y_area = px(46);
    let mut axes = equal_scale((x_lo, x_hi), (y_lo, y_hi), (width, height), y_area);
    for _ in 0..2 {
        let y_label = |value: &f64| format_tick(*value, axes.1.step);
        y_area = label_width(&plot, &axes.1.ticks, &y_label)? + px(46);
        axes = equal_scale((x_lo, x_hi), (y_lo, y_hi), (width, height), y_area);
    }
    let (x_axis, y_axis) = axes;
    let y_label = |value: &f64| format_tick(*value, y_axis.step);
    let mut chart = ChartBuilder::on(&plot)
        .margin(px(PATH_MARGIN))
        .margin_right(px(PATH_MARGIN_RIGHT))
        .x_label_area_size(px(PATH_X_LABELS))
        .y_label_area_size(y_area)
        .build_cartesian_2d(x_axis.coord(), y_axis.coord())?;
    configure_mesh(&mut chart, &x_axis, "x", "y", &y_label)?;
    let mut entries = Vec::new();
    for (idx, path) in shown.iter().enumerate() {
        let n = path.x.len().min(path.y.len());
        let (x, y) = (&path.x[..n], &path.y[..n]);
        let segments = segments(x, y, [false, false], &keep_extremes(&[x, y], n, MAX_POINTS));
        draw_curves(&mut chart, &segments, PALETTE[idx].mix(0.9), 1)?;
        if let Some(&start) = segments.first().and_then(|segment| segment.first()) {
            let marker = EmptyElement::at(start)
                + Circle::new((0, 0), px(6), INK.filled())
                + Circle::new((0, 0), px(4), PALETTE[idx].filled());
            chart.draw_series(std::iter::once(marker))?;
        }
        entries.push((path.name.clone(), PALETTE[idx]));
    }
    draw_legend(&legend_area, &entries, data.paths.len())?;
    let y = pos(62) + pos(27) * entries.len() as i32 + if data.paths.len() > entries.len() { pos(27) } else { 0 };
    legend_area.draw(&Circle::new((pos(17), y), px(6), INK.filled()))?;
    legend_area.draw_text("start", &text_style(19, &INK, (HPos::Left, VPos::Center)), (pos(38), y))?;
    Ok(())
}

/// The margins of the path panel's chart, and the height of its x labels, in figure pixels.
const PATH_MARGIN: u32 = 6;
const PATH_MARGIN_RIGHT: u32 = 18;
const PATH_X_LABELS: u32 = 52;

/// Axes over `x` and `y` (data ranges) at one scale, for a chart on an area of `size` whose y labels take
/// `y_area`: the span that needs the larger scale sets it, and the other span grows about its middle.
fn equal_scale(x: (f64, f64), y: (f64, f64), size: (u32, u32), y_area: u32) -> (Axis, Axis) {
    let plot_width = size.0.saturating_sub(y_area + px(PATH_MARGIN + PATH_MARGIN_RIGHT)).max(1) as f64;
    let plot_height = size.1.saturating_sub(px(2 * PATH_MARGIN + PATH_X_LABELS)).max(1) as f64;
    let (x_axis, y_axis) = (Axis::new(x.0, x.1, 5), Axis::new(y.0, y.1, 5));
    let per_pixel = ((x_axis.hi - x_axis.lo) / plot_width).max((y_axis.hi - y_axis.lo) / plot_height);
    if !per_pixel.is_finite() || per_pixel <= 0.0 {
        return (x_axis, y_axis);
    }
    let widen = |axis: &Axis, pixels: f64| {
        let (middle, half) = (axis.lo / 2.0 + axis.hi / 2.0, per_pixel * pixels / 2.0);
        Axis::exact(middle - half, middle + half, (pixels / f64::from(px(60))).round().max(2.0) as usize)
    };
    (widen(&x_axis, plot_width), widen(&y_axis, plot_height))
}

/// The width of the widest tick label, `label` of one of `ticks`.
fn label_width(area: &Area, ticks: &[f64], label: &dyn Fn(&f64) -> String) -> Result<u32, Box<dyn Error>> {
    let tick_style = text_style(18, &INK, (HPos::Right, VPos::Center));
    let mut widest = 0;
    for tick in ticks {
        widest = widest.max(area.estimate_text_size(&label(tick), &tick_style)?.0);
    }
    // Without a font file plotters estimates text at 1.24 times the size its SVG output gives the text.
    Ok(widest * 4 / 5)
}

/// A chart with a caption and room for the y tick labels `y_label` gives; its plotting area starts at least
/// `align_to` (a [`label_width`]) to the right of the usual place, so that panels stacked above each other align.
fn build_chart<'a, 'b>(
    area: &'a Area<'b>,
    caption: &str,
    x: &Axis,
    y: &Axis,
    y_label: &dyn Fn(&f64) -> String,
    align_to: u32,
) -> Result<Chart<'a, 'b>, Box<dyn Error>> {
    let own = label_width(area, &y.ticks, y_label)?;
    let chart = ChartBuilder::on(area)
        .caption(caption, bold_style(23, (HPos::Center, VPos::Top)))
        .margin(px(6))
        .margin_left(px(6) + align_to.saturating_sub(own))
        .margin_right(px(18))
        .x_label_area_size(px(52))
        .y_label_area_size(own + px(46))
        .build_cartesian_2d(x.coord(), y.coord())?;
    Ok(chart)
}

fn configure_mesh(
    chart: &mut Chart,
    x: &Axis,
    x_desc: &str,
    y_desc: &str,
    y_label: &dyn Fn(&f64) -> String,
) -> DrawResult {
    let x_label = |value: &f64| format_tick(*value, x.step);
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&x_label)
        .y_label_formatter(y_label)
        .light_line_style(TRANSPARENT)
        .bold_line_style(GRID.stroke_width(px(1)))
        .axis_style(AXIS.stroke_width(px(1)))
        .set_all_tick_mark_size(px(5))
        .label_style(text_style(18, &INK, (HPos::Center, VPos::Top)))
        .axis_desc_style(text_style(20, &INK, (HPos::Center, VPos::Top)))
        .draw()?;
    Ok(())
}

/// Draws each segment as a line; a segment of one point, which a line would not show, as a dot.
fn draw_curves<C: Color>(chart: &mut Chart, segments: &[Vec<(f64, f64)>], color: C, width: u32) -> DrawResult {
    let style = ShapeStyle { color: color.to_rgba(), filled: false, stroke_width: px(width) };
    for segment in segments {
        if let [point] = segment.as_slice() {
            chart.draw_series(std::iter::once(Circle::new(*point, px(3 + width), style.filled())))?;
        } else {
            chart.draw_series(LineSeries::new(segment.iter().copied(), style))?;
        }
    }
    Ok(())
}

/// A legend in its own strip beside a chart, so that it never hides a curve.
fn draw_legend(area: &Area, entries: &[(String, RGBColor)], n_total: usize) -> DrawResult {
    let text = text_style(19, &INK, (HPos::Left, VPos::Center));
    let mut y = pos(62);
    for (name, color) in entries {
        area.draw(&PathElement::new(vec![(pos(4), y), (pos(30), y)], color.stroke_width(px(3))))?;
        area.draw_text(&shorten(name, 12), &text, (pos(38), y))?;
        y += pos(27);
    }
    if n_total > entries.len() {
        let note = text_style(16, &MUTED, (HPos::Left, VPos::Center));
        area.draw_text(&format!("first {} of {n_total}", entries.len()), &note, (pos(4), y + pos(4)))?;
    }
    Ok(())
}

/// A panel with nothing to plot: its caption and a short message in the middle.
fn draw_message(area: &Area, caption: &str, message: &str) -> DrawResult {
    let (width, height) = area.dim_in_pixel();
    let center = width as i32 / 2;
    area.draw_text(caption, &bold_style(23, (HPos::Center, VPos::Top)), (center, pos(6)))?;
    area.draw_text(message, &text_style(20, &MUTED, (HPos::Center, VPos::Center)), (center, height as i32 / 2))?;
    Ok(())
}

/// A linear axis whose grid lines and labels sit at the ticks of an [`Axis`], not where plotters would put them.
struct Coord {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
}

impl Ranged for Coord {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        // Halved first, so that an axis from -f64::MAX to f64::MAX has a finite span.
        let fraction = (value / 2.0 - self.lo / 2.0) / (self.hi / 2.0 - self.lo / 2.0);
        // Saturating casts keep far-off points (a phase curve that ran away) off-canvas rather than wrapping.
        limit.0 + (f64::from(limit.1 - limit.0) * fraction).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

fn shorten(name: &str, max_chars: usize) -> String {
    if name.chars().count() <= max_chars {
        name.to_string()
    } else {
        let head: String = name.chars().take(max_chars - 1).collect();
        format!("{head}…")
    }
}

/// An axis range with round tick positions; `step` is the tick spacing, for formatting labels.
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
    step: f64,
}

impl Axis {
    /// An axis spanning the finite values of `values`.
    fn of(values: &[f64], n_ticks: usize) -> Axis {
        let (lo, hi) = finite_range(values);
        Axis::new(lo, hi, n_ticks)
    }

    /// An axis over `lo..hi`, widened a little so that curves clear the frame, and to a nonzero span when the
    /// data is constant; no finite data (`lo > hi`) gives `0..1`.
    fn new(lo: f64, hi: f64, n_ticks: usize) -> Axis {
        let (lo, hi) = if !(lo.is_finite() && hi.is_finite()) || lo > hi {
            (0.0, 1.0)
        } else if hi - lo <= 1e-12 * lo.abs().max(hi.abs()) || hi == lo {
            let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            (lo - pad, hi + pad)
        } else {
            let pad = 0.04 * hi - 0.04 * lo;
            ((lo - pad).max(-f64::MAX), (hi + pad).min(f64::MAX))
        };
        Axis::exact(lo, hi, n_ticks)
    }

    /// An axis over exactly `lo..hi` (finite, `lo < hi`), with about `n_ticks` ticks.
    fn exact(lo: f64, hi: f64, n_ticks: usize) -> Axis {
        // Divided before subtracting, so that a span beyond f64::MAX (±1e308 data) still gives a finite step.
        let step = nice_step(hi / n_ticks.max(1) as f64 - lo / n_ticks.max(1) as f64);
        let first = (lo / step).ceil() as i64;
        let last = (hi / step).floor() as i64;
        // Rounding at the ends of f64 could give a runaway count; a bare axis is better than a hang.
        let ticks = if (0..=4 * n_ticks as i64).contains(&last.saturating_sub(first)) {
            (first..=last).map(|idx| idx as f64 * step).collect()
        } else {
            Vec::new()
        };
        Axis { lo, hi, ticks, step }
    }

    fn coord(&self) -> Coord {
        Coord { lo: self.lo, hi: self.hi, ticks: self.ticks.clone() }
    }
}

/// The round number (1, 2 or 5 times a power of ten) nearest above `rough`.
pub(crate) fn nice_step(rough: f64) -> f64 {
    let rough = if rough.is_finite() && rough > 0.0 { rough } else { 1.0 };
    let decade = 10f64.powf(rough.log10().floor());
    let mantissa = rough / decade;
    let nice = if mantissa <= 1.0 {
        1.0
    } else if mantissa <= 2.0 {
        2.0
    } else if mantissa <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * decade
}

/// The smallest and largest finite value, or `(inf, -inf)` when there is none.
fn finite_range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .filter(|value| value.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &value| (lo.min(value), hi.max(value)))
}

/// A tick label: plain decimals for ordinary magnitudes, `m×10ⁿ` for tiny or huge ones; a true minus sign.
fn format_tick(value: f64, step: f64) -> String {
    let magnitude = value.abs().max(step.abs());
    let text = if value == 0.0 || value.abs() < 1e-9 * step.abs() {
        "0".to_string()
    } else if !(1e-3..1e5).contains(&magnitude) || step.abs() < 1e-3 {
        scientific(value)
    } else {
        let decimals = (1 - step.abs().log10().floor() as i32).clamp(0, 8) as usize;
        trim_zeros(&format!("{value:.decimals$}"))
    };
    text.replace('-', "−")
}

/// `value` as `m×10ⁿ` with at most two decimals in the mantissa, `1×10ⁿ` kept whole for a steady look.
/// `−11` as `⁻¹¹`: the exponent of a tick label.
pub(crate) fn superscript(text: &str) -> String {
    text.chars()
        .map(|c| match c {
            '−' | '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            other => other,
        })
        .collect()
}

fn scientific(value: f64) -> String {
    let formatted = format!("{value:.2e}");
    let (mantissa, exponent) = formatted.split_once('e').unwrap_or((&formatted, "0"));
    format!("{}×10{}", trim_zeros(mantissa), superscript(exponent))
}

fn trim_zeros(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text.to_string()
    }
}

/// The drift of one conserved quantity from its first finite value: relative, or absolute when that value is 0.
struct Drift {
    values: Vec<f64>,
    relative: bool,
}

impl Drift {
    fn of(values: &[f64]) -> Drift {
        let initial = values.iter().copied().find(|value| value.is_finite()).unwrap_or(0.0);
        let relative = initial != 0.0;
        let scale = if relative { initial.abs() } else { 1.0 };
        Drift { values: values.iter().map(|&value| (value - initial) / scale).collect(), relative }
    }
}

/// The vertical scale of the drift panel. Linear, unless the drifts' peaks differ by more than a factor 1000:
/// then symmetric-logarithmic (`symlog`), linear within ±`threshold` and one unit per decade beyond, so that a
/// drift of 1e-15 and one of 1e-6 both stay visible.
struct DriftScale {
    axis: Axis,
    threshold: Option<f64>,
}

impl DriftScale {
    fn new(drifts: &[Drift]) -> DriftScale {
        let peaks: Vec<f64> = drifts
            .iter()
            .map(|drift| {
                drift.values.iter().filter(|value| value.is_finite()).fold(0.0, |peak, value| value.abs().max(peak))
            })
            .filter(|&peak| peak > 0.0)
            .collect();
        let largest = peaks.iter().copied().fold(0.0, f64::max);
        let smallest = peaks.iter().copied().fold(f64::INFINITY, f64::min);
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for drift in drifts {
            let (a, b) = finite_range(&drift.values);
            lo = lo.min(a).min(0.0);
            hi = hi.max(b).max(0.0);
        }
        if peaks.len() < 2 || largest <= 1e3 * smallest {
            let axis = if largest == 0.0 { Axis::new(-1.0, 1.0, 4) } else { Axis::new(lo, hi, 6) };
            return DriftScale { axis, threshold: None };
        }
        let threshold = 10f64.powf(smallest.log10().floor());
        let scale = DriftScale { axis: Axis::new(0.0, 1.0, 1), threshold: Some(threshold) };
        let (lo, hi) = (scale.map(lo).floor().min(0.0), scale.map(hi).ceil().max(0.0));
        let decades = (hi - lo).max(1.0);
        let step = (decades / 6.0).ceil();
        let first = (lo / step).ceil() as i64;
        let last = (hi / step).floor() as i64;
        let ticks = (first..=last).map(|idx| idx as f64 * step).collect();
        let pad = 0.04 * (hi - lo).max(1.0);
        DriftScale { axis: Axis { lo: lo - pad, hi: hi + pad, ticks, step }, threshold: Some(threshold) }
    }

    /// Where a drift sits on the axis.
    fn map(&self, value: f64) -> f64 {
        match self.threshold {
            None => value,
            Some(threshold) => {
                // Logarithms subtracted, not divided, so that a drift near f64::MAX maps to a finite place.
                let size = value.abs();
                let mapped = if size <= threshold { size / threshold } else { 1.0 + size.log10() - threshold.log10() };
                mapped.copysign(value)
            }
        }
    }

    /// The label of a tick at axis position `position`.
    fn label(&self, position: f64) -> String {
        match self.threshold {
            None => format_tick(position, self.axis.step),
            Some(threshold) => {
                let size = position.abs();
                let value = if size <= 1.0 {
                    size * threshold
                } else {
                    10f64.powf(threshold.log10() + size - 1.0).min(f64::MAX)
                };
                if value == 0.0 {
                    "0".to_string()
                } else {
                    scientific(value.copysign(position)).replace('-', "−")
                }
            }
        }
    }
}

/// The samples of `series` against `time` as lines, broken at non-finite samples (and where an angle wraps) and
/// decimated.
fn time_segments(time: &[f64], series: &Series) -> Vec<Vec<(f64, f64)>> {
    let n = time.len().min(series.values.len());
    let (time, values) = (&time[..n], &series.values[..n]);
    let shown = drawn(series);
    segments(time, values, [false, series.angle], &keep_extremes(&[&shown[..n]], n, MAX_POINTS))
}

/// The phase curve (q, q') as lines, broken at non-finite samples (and where q wraps) and decimated.
fn phase_segments(q: &Series, v: &Series) -> Vec<Vec<(f64, f64)>> {
    let n = q.values.len().min(v.values.len());
    let shown = drawn(q);
    let indices = keep_extremes(&[&shown[..n], &v.values[..n]], n, MAX_POINTS);
    segments(&q.values[..n], &v.values[..n], [q.angle, false], &indices)
}

/// The values of `series` as drawn: an angle wrapped to (−π, π].
fn drawn(series: &Series) -> Vec<f64> {
    if series.angle {
        series.values.iter().map(|&value| wrap(value)).collect()
    } else {
        series.values.clone()
    }
}

/// Whether `series` is an angle that leaves (−π, π], so that wrapping changes its curve.
fn wraps(series: &Series) -> bool {
    series.angle && series.values.iter().any(|&value| value.is_finite() && turn(value) != 0.0)
}

/// `angle` wrapped to (−π, π].
fn wrap(angle: f64) -> f64 {
    angle - TAU * turn(angle)
}

/// Which turn `angle` is in: k for angles in (2πk − π, 2πk + π].
fn turn(angle: f64) -> f64 {
    ((angle - PI) / TAU).ceil()
}

/// The indices (ascending) to draw of `n` samples: all of them when there are at most `budget`, else the first and
/// last sample, each bucket's minimum and maximum of every column, and each bucket's first non-finite sample so
/// that gaps stay gaps.
fn keep_extremes(columns: &[&[f64]], n: usize, budget: usize) -> Vec<usize> {
    if n <= budget {
        return (0..n).collect();
    }
    let n_buckets = (budget / (2 * columns.len().max(1) + 1)).max(1);
    let bucket_len = n.div_ceil(n_buckets);
    let mut kept = vec![0, n - 1];
    for start in (0..n).step_by(bucket_len) {
        let end = (start + bucket_len).min(n);
        if let Some(gap) = (start..end).find(|&idx| columns.iter().any(|column| !column[idx].is_finite())) {
            kept.push(gap);
        }
        for column in columns {
            let finite = (start..end).filter(|&idx| column[idx].is_finite());
            if let Some(idx) = finite.clone().min_by(|&a, &b| column[a].total_cmp(&column[b])) {
                kept.push(idx);
            }
            if let Some(idx) = finite.max_by(|&a, &b| column[a].total_cmp(&column[b])) {
                kept.push(idx);
            }
        }
    }
    kept.sort_unstable();
    kept.dedup();
    kept
}

/// The points `(x[idx], y[idx])` for `idx` in `indices`, split into runs of finite points. The coordinates `wrap`
/// marks are angles, drawn wrapped to (−π, π]: a run also ends where one of them wraps, drawn on to the edge it
/// leaves by, and the next run starts at the opposite edge; it ends too where a wrapped coordinate jumps by more
/// than π between kept samples, so that no line crosses the plot from edge to edge.
fn segments(x: &[f64], y: &[f64], wrap_axis: [bool; 2], indices: &[usize]) -> Vec<Vec<(f64, f64)>> {
    let shown = |value: f64, angle: bool| if angle { wrap(value) } else { value };
    let mut res = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    let mut previous: Option<([f64; 2], [f64; 2])> = None;
    for &idx in indices {
        let raw = [x[idx], y[idx]];
        if !(raw[0].is_finite() && raw[1].is_finite()) {
            if !current.is_empty() {
                res.push(std::mem::take(&mut current));
            }
            previous = None;
            continue;
        }
        let point = [shown(raw[0], wrap_axis[0]), shown(raw[1], wrap_axis[1])];
        if let Some((raw_before, before)) = previous {
            let broken: Vec<usize> = (0..2)
                .filter(|&a| wrap_axis[a] && (turn(raw_before[a]) != turn(raw[a]) || (point[a] - before[a]).abs() > PI))
                .collect();
            if !broken.is_empty() {
                let edges = match broken[..] {
                    [a] => edge_points(a, (raw_before, before), (raw, point)),
                    _ => None,
                };
                if let Some((end, _)) = edges {
                    current.push(end);
                }
                res.push(std::mem::take(&mut current));
                if let Some((_, start)) = edges {
                    current.push(start);
                }
            }
        }
        current.push((point[0], point[1]));
        previous = Some((raw, point));
    }
    if !current.is_empty() {
        res.push(current);
    }
    res
}

/// Where a line from `from` to `to` (each as raw and drawn values) leaves the edge of axis `a`'s (−π, π] and
/// comes back at the other edge, when it wraps once: the last point of one run and the first of the next.
fn edge_points(a: usize, from: ([f64; 2], [f64; 2]), to: ([f64; 2], [f64; 2])) -> Option<((f64, f64), (f64, f64))> {
    let (turn_from, turn_to) = (turn(from.0[a]), turn(to.0[a]));
    if (turn_to - turn_from).abs() != 1.0 {
        return None;
    }
    let (edge, boundary) = if turn_to > turn_from { (PI, PI + TAU * turn_from) } else { (-PI, -PI + TAU * turn_from) };
    let fraction = ((boundary - from.0[a]) / (to.0[a] - from.0[a])).clamp(0.0, 1.0);
    let o = 1 - a;
    let other = from.1[o] + fraction * (to.1[o] - from.1[o]);
    let at = |value: f64| if a == 0 { (value, other) } else { (other, value) };
    fraction.is_finite().then(|| (at(edge), at(-edge)))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Fails unless `svg` is one `<svg>` element whose tags open and close in
    /// order (XML-ish: no attribute or entity is checked).
    #[track_caller]
    pub(crate) fn assert_balanced(svg: &str) {
        let mut open: Vec<&str> = Vec::new();
        let mut roots = 0;
        let mut rest = svg;
        while let Some(start) = rest.find('<') {
            let end = start + rest[start..].find('>').expect("every tag is closed by '>'");
            let tag = &rest[start + 1..end];
            rest = &rest[end + 1..];
            if tag.starts_with('?') || tag.starts_with('!') {
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(open.pop(), Some(name.trim()), "</{name}> closes another element");
            } else {
                let name = tag.split(|c: char| c.is_whitespace() || c == '/').next().unwrap_or("");
                if open.is_empty() {
                    assert_eq!(name, "svg", "the root element is <svg>");
                    roots += 1;
                }
                if !tag.ends_with('/') {
                    open.push(name);
                }
            }
        }
        assert!(open.is_empty(), "unclosed elements: {open:?}");
        assert_eq!(roots, 1, "one root element");
    }

    fn series(name: &str, values: Vec<f64>) -> Series {
        Series { name: name.to_string(), values, angle: false }
    }

    /// A double-pendulum-like run: two coupled oscillations, an energy with a tiny bounded wobble, a momentum.
    fn pendulum_like(n: usize) -> PlotData {
        let time: Vec<f64> = (0..n).map(|idx| 20.0 * idx as f64 / (n - 1) as f64).collect();
        let a: Vec<f64> = time.iter().map(|t| 1.2 * (2.1 * t).sin() + 0.4 * (5.3 * t).cos()).collect();
        let b: Vec<f64> = time.iter().map(|t| 2.0 * (1.3 * t).cos() * (0.9 * t).sin() + 0.5).collect();
        let a_dot: Vec<f64> = time.iter().map(|t| 2.52 * (2.1 * t).cos() - 2.12 * (5.3 * t).sin()).collect();
        let b_dot: Vec<f64> = time
            .iter()
            .map(|t| -2.6 * (1.3 * t).sin() * (0.9 * t).sin() + 1.8 * (1.3 * t).cos() * (0.9 * t).cos())
            .collect();
        let energy: Vec<f64> = time.iter().map(|t| -14.7 * (1.0 + 3e-11 * (3.0 * t).sin() + 1e-12 * t)).collect();
        let momentum: Vec<f64> = time.iter().map(|t| 2e-15 * (7.0 * t).sin()).collect();
        PlotData {
            title: "planar double pendulum".to_string(),
            subtitle: "dop853, rtol 1e-10, 12345 steps".to_string(),
            time,
            coordinates: vec![series("a", a), series("b", b)],
            velocities: vec![series("a'", a_dot), series("b'", b_dot)],
            invariants: vec![series("energy", energy), series("p_z", momentum)],
            paths: vec![],
        }
    }

    #[track_caller]
    fn check_svg(data: &PlotData, name: &str, expect: &[&str]) -> String {
        let svg = svg(data).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "not an SVG: {}", &svg[..80]);
        assert!(!svg.contains("NaN"), "non-finite coordinates in {name}");
        assert_balanced(&svg);
        for text in expect {
            assert!(svg.contains(text), "{name} lacks {text:?}");
        }
        svg
    }

    #[test]
    fn pendulum_figure() {
        let svg = check_svg(
            &pendulum_like(2001),
            "pendulum.svg",
            &[
                "planar double pendulum",
                "dop853, rtol 1e-10",
                "\na\n</text>",
                "\nb\n</text>",
                "Phase portrait of a",
                "Phase portrait of b",
                "energy",
                "p_z (abs.)",
            ],
        );
        assert!(svg.contains("×10⁻"), "drift ticks are not scientific");

        // With the bobs' paths, two phase portraits side by side below them; of three, the first alone.
        let mut data = pendulum_like(2001);
        let bob = |a: &[f64]| Path {
            name: "particle 1".into(),
            x: a.iter().map(|a| a.sin()).collect(),
            y: a.iter().map(|a| -a.cos()).collect(),
        };
        data.paths = vec![bob(&data.coordinates[0].values)];
        check_svg(&data, "paths.svg", &["Path in the plane", "particle 1", "start", "Phase of a", "Phase of b"]);
        data.coordinates.push(series("c", data.time.clone()));
        data.velocities.push(series("c'", vec![1.0; data.time.len()]));
        let svg = check_svg(&data, "paths3.svg", &["Phase portrait of a (first of 3)"]);
        assert!(!svg.contains("Phase of b"));
    }

    #[test]
    fn degenerate_inputs() {
        let empty = PlotData {
            title: "empty & <odd>".to_string(),
            subtitle: String::new(),
            time: vec![],
            coordinates: vec![],
            velocities: vec![],
            invariants: vec![],
            paths: vec![],
        };
        let svg = check_svg(&empty, "empty.svg", &["empty &amp; &lt;odd&gt;", "no samples", "no coordinates"]);
        assert!(!svg.contains("Drift"), "a drift panel without conserved quantities");

        let single = PlotData {
            title: "one sample".to_string(),
            subtitle: String::new(),
            time: vec![0.0],
            coordinates: vec![series("x", vec![1.0])],
            velocities: vec![series("x'", vec![0.0])],
            invariants: vec![series("E", vec![3.0])],
            paths: vec![Path { name: "particle 1".into(), x: vec![1.0], y: vec![2.0] }],
        };
        check_svg(&single, "single.svg", &["one sample", "Phase portrait of x"]);

        let n = 100;
        let bad = |idx: usize| {
            if idx % 7 == 3 {
                f64::NAN
            } else if idx == 50 {
                f64::INFINITY
            } else {
                idx as f64
            }
        };
        let many = PlotData {
            title: "chain".to_string(),
            subtitle: "constant, non-finite, short and many series".to_string(),
            time: (0..n).map(|idx| idx as f64).collect(),
            coordinates: (0..50).map(|idx| series(&format!("q{idx}"), (0..n).map(bad).collect())).collect(),
            velocities: vec![series("q0'", vec![2.0; n])],
            invariants: vec![series("E", vec![5.0; n]), series("L", vec![f64::NAN; 3])],
            paths: (0..12)
                .map(|idx| Path { name: format!("particle {idx}"), x: (0..n).map(bad).collect(), y: vec![1.0; n] })
                .collect(),
        };
        check_svg(&many, "many.svg", &["first 8 of 50", "Phase portrait of q0 (first of 50)", "first 8 of 12"]);

        let huge = PlotData {
            title: "extremes".to_string(),
            subtitle: String::new(),
            time: vec![0.0, 1e-300, 2e-300],
            coordinates: vec![series("x", vec![-f64::MAX, 0.0, f64::MAX])],
            velocities: vec![series("x'", vec![5e-324, 0.0, 1e-323])],
            invariants: vec![series("E", vec![1.0, f64::MAX, -f64::MAX]), series("P", vec![0.0, 1e-300, 0.0])],
            paths: vec![Path { name: "far".into(), x: vec![-f64::MAX, 0.0, f64::MAX], y: vec![0.0, 1e-300, f64::NAN] }],
        };
        check_svg(&huge, "huge.svg", &["extremes"]);
    }

    #[test]
    fn decimation_keeps_extremes_and_gaps() {
        let n = 100_000;
        let mut values: Vec<f64> = (0..n).map(|idx| (idx as f64 * 0.01).sin()).collect();
        values[31_337] = 40.0;
        values[70_000] = f64::NAN;
        let kept = keep_extremes(&[&values], n, MAX_POINTS);
        assert!(kept.len() <= MAX_POINTS + 2, "{} points kept", kept.len());
        assert!(kept.contains(&31_337) && kept.contains(&70_000) && kept.contains(&(n - 1)));
        let time: Vec<f64> = (0..n).map(|idx| idx as f64).collect();
        assert_eq!(time_segments(&time, &series("x", values)).len(), 2);
    }

    /// An angle that swings and then goes over the top again and again, both ways, also decimated.
    #[test]
    fn wrapped_angles_have_no_jump_within_a_line() {
        for n in [500, 3000, 50_000] {
            let time: Vec<f64> = (0..n).map(|idx| 60.0 * idx as f64 / (n - 1) as f64).collect();
            let spin: Vec<f64> = time.iter().map(|t| 1.1 * t + 2.5 * (0.4 * t).sin() - 0.02 * t * t).collect();
            let rate: Vec<f64> = time.iter().map(|t| 1.1 + (0.4 * t).cos() - 0.04 * t).collect();
            let (q, v) = (Series { angle: true, ..series("ph", spin.clone()) }, series("ph'", rate));
            let (lines, phase) = (time_segments(&time, &q), phase_segments(&q, &v));
            let jumps = |segments: &[Vec<(f64, f64)>], of: fn(&(f64, f64)) -> f64| {
                segments
                    .iter()
                    .flat_map(|s| s.windows(2).map(move |w| (of(&w[1]) - of(&w[0])).abs()))
                    .fold(0.0, f64::max)
            };
            assert!(jumps(&lines, |p| p.1) <= PI, "{n} samples: a jump of {} in a line", jumps(&lines, |p| p.1));
            assert!(jumps(&phase, |p| p.0) <= PI, "{n} samples: a jump in a phase curve");
            for (t, a) in lines.iter().flatten() {
                assert!(-PI <= *a && *a <= PI, "{a} at t = {t} not wrapped");
            }
            // It crosses ±π many times: as many breaks, each line ending on the edge it leaves by.
            let turns = spin.windows(2).filter(|w| turn(w[0]) != turn(w[1])).count();
            assert!(turns > 5 && lines.len() == turns + 1, "{n}: {} lines for {turns} turns", lines.len());
            for pair in lines.windows(2) {
                let (end, start) = (pair[0].last().unwrap(), pair[1][0]);
                assert!(end.1.abs() == PI && start.1 == -end.1 && end.0 == start.0, "{end:?} then {start:?}");
            }
            // Drawn unwrapped, the same data is one line.
            assert_eq!(time_segments(&time, &series("ph", spin)).len(), 1);
        }
        assert_eq!((wrap(PI), wrap(-PI), wrap(3.0 * PI), wrap(7.0)), (PI, PI, PI, 7.0 - TAU));
    }

    /// Paths at equal scale: a unit of x is as long on the page as a unit of y.
    #[test]
    fn paths_are_drawn_at_equal_scale() {
        let size = (px(500), px(380));
        for (x, y) in [((-2.0, 2.0), (-2.0, 0.0)), ((0.0, 1.0), (-30.0, 30.0)), ((5.0, 5.0), (1.0, 1.0))] {
            let (x_axis, y_axis) = equal_scale(x, y, size, px(60));
            let width = f64::from(size.0 - px(60 + PATH_MARGIN + PATH_MARGIN_RIGHT));
            let height = f64::from(size.1 - px(2 * PATH_MARGIN + PATH_X_LABELS));
            let (sx, sy) = ((x_axis.hi - x_axis.lo) / width, (y_axis.hi - y_axis.lo) / height);
            assert!((sx / sy - 1.0).abs() < 1e-9, "{x:?} {y:?}: scales {sx} and {sy}");
            assert!(x_axis.lo <= x.0 && x.1 <= x_axis.hi && y_axis.lo <= y.0 && y.1 <= y_axis.hi);
        }
    }

    #[test]
    fn tick_labels() {
        assert_eq!(format_tick(0.25, 0.05), "0.25");
        assert_eq!(format_tick(-2.0, 1.0), "−2");
        assert_eq!(format_tick(2e-14, 1e-14), "2×10⁻¹⁴");
        assert_eq!(format_tick(1.5e6, 5e5), "1.5×10⁶");
        assert_eq!(format_tick(1e-18, 0.5), "0");
    }
}
