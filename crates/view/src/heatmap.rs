//! The heat map of a 2-D sweep, one SVG: a cell per run at (first axis, second
//! axis), coloured by one column (the Lyapunov exponent: the chaos map), with a
//! colour bar, axis labels named after the grid and a title.
//!
//! Enter at [`HeatMap::new`] (before running), [`HeatMap::add`] per row as
//! the sweep streams (one `f32` per cell: at most [`MAX_CELLS`]), and
//! [`HeatMap::svg`] for the SVG text. A map that cannot be drawn is a
//! [`HeatMapError`] with its facts, which the front end words. Colours are
//! viridis (perceptually uniform, legible in grey and to colour-blind readers);
//! the range spans the 0.5th to 99.5th percentile so that a few outliers do not
//! wash out the map, and the bar's ends say when values were clipped. The drift
//! of H is shown as log₁₀. Failed or missing runs are grey. Cells of equal colour
//! in a row are drawn as one rectangle, which keeps a 200×200 map's file small.

use crate::plot::{nice_step, pos, px, superscript, text_style, FONT};
use crate::DrawError;
use mech::{Axis, SweepHeader, TableRow};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::error::Error;

const WIDTH: u32 = 960;
const HEIGHT: u32 = 860;
const INK: RGBColor = RGBColor(0x22, 0x22, 0x22);
const MUTED: RGBColor = RGBColor(0x66, 0x66, 0x66);
const MISSING: RGBColor = RGBColor(0xbb, 0xbb, 0xbb);
/// Matplotlib's viridis at eleven evenly spaced points.
const VIRIDIS: [(u8, u8, u8); 11] = [
    (0x44, 0x01, 0x54),
    (0x48, 0x28, 0x78),
    (0x41, 0x44, 0x87),
    (0x35, 0x5f, 0x8d),
    (0x2a, 0x78, 0x8e),
    (0x21, 0x91, 0x8c),
    (0x22, 0xa8, 0x84),
    (0x44, 0xbf, 0x70),
    (0x7a, 0xd1, 0x51),
    (0xbc, 0xdf, 0x27),
    (0xfd, 0xe7, 0x25),
];

/// The most cells a heat map holds: one `f32` each, 4 MB, whatever the sweep;
/// an SVG of more cells than a screen has pixels would show nothing more.
pub const MAX_CELLS: usize = 1_000_000;

/// The column a colour names: `lyapunov`, `drift`, a final coordinate or velocity (`a`, `a'`), or any column.
fn column_of(color: &str) -> String {
    match color {
        "lyapunov" | "energy_drift" | "t_final" => color.to_string(),
        "drift" => "energy_drift".into(),
        c if c.starts_with("final_") => c.to_string(),
        c => format!("final_{c}"),
    }
}

/// Why a sweep has no heat map, found before any run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HeatMapError {
    /// The grid does not have two axes.
    NotTwoDimensional {
        /// How many axes it has.
        axes: usize,
    },
    /// An axis lists values that are not evenly spaced, which cells of one
    /// width cannot show.
    UnevenAxis {
        /// The axis's name.
        name: String,
    },
    /// The grid has more than [`MAX_CELLS`] cells.
    TooManyCells {
        /// The points along the first axis.
        first: usize,
        /// The points along the second axis.
        second: usize,
    },
    /// The colour names no column of the sweep.
    UnknownColor {
        /// The colour asked for.
        color: String,
        /// The colours that could be drawn, in the order of the columns.
        known: Vec<String>,
    },
}

/// What a heat map draws, gathered row by row as a sweep streams: one value
/// per cell (the colour column, as log₁₀ for the drift), and the counts the
/// subtitle gives.
pub struct HeatMap {
    ax: Axis,
    ay: Axis,
    /// The column drawn, and its index among a row's values.
    column: String,
    value: usize,
    /// Whether cells hold log₁₀ of the values.
    log: bool,
    /// Row-major by the first axis: `cells[i·ny + j]`; NaN where no colour (yet).
    cells: Vec<f32>,
    rows: usize,
    failed: usize,
    header: SweepHeader,
}

impl HeatMap {
    /// An empty map for the sweep of `header`, coloured by `color`; refused
    /// before any run when the grid is not 2-D, has more than [`MAX_CELLS`]
    /// cells, or the colour is not a column.
    pub fn new(header: &SweepHeader, color: &str) -> Result<HeatMap, HeatMapError> {
        let axes = header.axes().unwrap_or_default();
        let [ax, ay] = axes.as_slice() else {
            return Err(HeatMapError::NotTwoDimensional { axes: axes.len() });
        };
        if let Some(a) = [ax, ay].into_iter().find(|a| !a.is_even()) {
            return Err(HeatMapError::UnevenAxis { name: a.name.clone() });
        }
        let cells = ax.count * ay.count;
        if cells > MAX_CELLS {
            return Err(HeatMapError::TooManyCells { first: ax.count, second: ay.count });
        }
        let column = column_of(color);
        let lyapunov_off = header.meta("lyapunov") == Some("off");
        let drawable = |c: &str| !(lyapunov_off && c == "lyapunov");
        let value = header.value_index(&column).filter(|_| drawable(&column)).ok_or_else(|| {
            let mut known = vec!["drift".to_string()];
            if !lyapunov_off {
                known.insert(0, "lyapunov".into());
            }
            known.extend(header.columns.iter().filter_map(|c| c.strip_prefix("final_").map(str::to_string)));
            HeatMapError::UnknownColor { color: color.to_string(), known }
        })?;
        Ok(HeatMap {
            ax: ax.clone(),
            ay: ay.clone(),
            log: column == "energy_drift",
            column,
            value,
            cells: vec![f32::NAN; cells],
            rows: 0,
            failed: 0,
            header: header.clone(),
        })
    }

    /// Takes a row's value into its cell.
    pub fn add(&mut self, row: &TableRow) {
        self.rows += 1;
        if !row.failure.is_empty() {
            self.failed += 1;
        }
        let v = row.values[self.value];
        let v = if self.log { v.log10() } else { v };
        if let Some(cell) = self.cells.get_mut(row.run) {
            // Finite values beyond f32's range keep their sign at its end.
            let limit = f64::from(f32::MAX);
            *cell = if v.is_finite() { v.clamp(-limit, limit) as f32 } else { f32::NAN };
        }
    }

    /// The map as SVG text; cells without a row (a sweep interrupted, a
    /// shard) are grey like failed runs.
    pub fn svg(&self) -> Result<String, DrawError> {
        Ok(self.render()?)
    }
}

/// How values (log₁₀ of them on a log scale) map to colours.
struct Scale {
    lo: f64,
    hi: f64,
    log: bool,
    clipped_lo: bool,
    clipped_hi: bool,
}

impl Scale {
    fn new(values: &[f32], log: bool) -> Scale {
        let mut v: Vec<f32> = values.iter().copied().filter(|x| x.is_finite()).collect();
        v.sort_by(f32::total_cmp);
        if v.is_empty() {
            return Scale { lo: 0.0, hi: 1.0, log, clipped_lo: false, clipped_hi: false };
        }
        let at = |q: f64| f64::from(v[((v.len() - 1) as f64 * q).round() as usize]);
        let (mut lo, mut hi) = (at(0.005), at(0.995));
        if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
            let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            (lo, hi) = (lo - pad, hi + pad);
        }
        let (min, max) = (f64::from(v[0]), f64::from(v[v.len() - 1]));
        Scale { lo, hi, log, clipped_lo: min < lo, clipped_hi: max > hi }
    }

    /// Position in 0..=1 of a cell's value, None when it has no colour.
    fn fraction(&self, x: f32) -> Option<f64> {
        let x = f64::from(x);
        x.is_finite().then(|| ((x - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0))
    }
}

fn viridis(f: f64) -> RGBColor {
    let x = f.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let w = x - k as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * w).round() as u8;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

fn describe(column: &str) -> String {
    match column {
        "lyapunov" => "largest Lyapunov exponent λ".into(),
        "energy_drift" => "relative drift of H".into(),
        "t_final" => "time reached".into(),
        c => format!("final {}", c.trim_start_matches("final_")),
    }
}

impl HeatMap {
    fn render(&self) -> Result<String, Box<dyn Error>> {
        let (ax, ay, column) = (&self.ax, &self.ay, &self.column);
        let scale = Scale::new(&self.cells, self.log);
        // Cell colours, [i][j] for the i-th value of the first axis and j-th of the second.
        let mut cells = vec![vec![MISSING; ay.count]; ax.count];
        for (k, &x) in self.cells.iter().enumerate() {
            if let Some(f) = scale.fraction(x) {
                cells[k / ay.count][k % ay.count] = viridis(f);
            }
        }
        let edges = |a: &Axis| {
            let half = if a.count > 1 { 0.5 * (a.stop - a.start) / (a.count - 1) as f64 } else { 0.5 };
            let (lo, hi) = (a.start - half, a.stop + half);
            if lo <= hi {
                (lo, hi, half)
            } else {
                (hi, lo, half)
            }
        };
        let (x_lo, x_hi, hx) = edges(ax);
        let (y_lo, y_hi, hy) = edges(ay);

        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (px(WIDTH), px(HEIGHT))).into_drawing_area();
            root.fill(&WHITE)?;
            let (header, body) = root.split_vertically(px(86));
            let center = pos(WIDTH as i32 / 2);
            let model = self.header.meta("model").unwrap_or("sweep");
            let title = format!("{model}: {}", describe(column));
            let bold = TextStyle::from((FONT, px(26)).into_font().style(FontStyle::Bold))
                .color(&INK)
                .pos(Pos::new(HPos::Center, VPos::Top));
            header.draw_text(&title, &bold, (center, pos(16)))?;
            let failed = self.failed;
            let mut subtitle = format!(
                "{} × {} runs to t = {}, {} at rtol {}",
                ax.count,
                ay.count,
                self.header.meta("until").unwrap_or("?").trim_end_matches(".0"),
                self.header.meta("method").unwrap_or("?"),
                self.header.meta("rtol").unwrap_or("?"),
            );
            if column == "lyapunov" {
                subtitle.push_str(", twin at d₀ = 10⁻⁸ renormalized every time unit");
            }
            let missing = (ax.count * ay.count).saturating_sub(self.rows);
            if failed > 0 || missing > 0 {
                subtitle.push_str(&format!("; grey: {} failed or missing", failed + missing));
            }
            header.draw_text(&subtitle, &text_style(17, &MUTED, (HPos::Center, VPos::Top)), (center, pos(52)))?;

            let (left, right) = body.split_horizontally(px(WIDTH - 170));
            let mut chart = ChartBuilder::on(&left.margin(px(4), px(10), px(10), px(10)))
                .x_label_area_size(px(56))
                .y_label_area_size(px(74))
                .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(ax.name.as_str())
                .y_desc(ay.name.as_str())
                .x_labels(8)
                .y_labels(8)
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&|v| tick(*v))
                .axis_style(MUTED.stroke_width(px(1)))
                .set_all_tick_mark_size(px(5))
                .label_style(text_style(17, &INK, (HPos::Center, VPos::Top)))
                .axis_desc_style(text_style(21, &INK, (HPos::Center, VPos::Top)))
                .draw()?;
            // One rectangle per run of equal colour along the first axis.
            let mut rects = Vec::new();
            for j in 0..ay.count {
                let y = ay.value(j);
                let mut i = 0;
                while i < ax.count {
                    let c = cells[i][j];
                    let mut end = i + 1;
                    while end < ax.count && cells[end][j] == c {
                        end += 1;
                    }
                    let (x0, x1) = (ax.value(i) - hx, ax.value(end - 1) + hx);
                    rects.push(Rectangle::new([(x0, y - hy), (x1, y + hy)], c.filled()));
                    i = end;
                }
            }
            chart.draw_series(rects)?;

            draw_colorbar(&right, &scale, &describe(column))?;
            root.present()?;
        }
        let big = format!("width=\"{}\" height=\"{}\"", px(WIDTH), px(HEIGHT));
        Ok(svg.replacen(&big, &format!("width=\"{WIDTH}\" height=\"{HEIGHT}\" shape-rendering=\"crispEdges\""), 1))
    }
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

fn draw_colorbar(area: &Area, scale: &Scale, label: &str) -> Result<(), Box<dyn Error>> {
    let (top, bottom) = (pos(40), area.dim_in_pixel().1 as i32 - pos(76));
    let (x0, x1) = (pos(18), pos(46));
    let steps = 256;
    let height = f64::from(bottom - top);
    for s in 0..steps {
        let ya = bottom - (height * s as f64 / steps as f64).round() as i32;
        let yb = bottom - (height * (s + 1) as f64 / steps as f64).round() as i32;
        let c = viridis((s as f64 + 0.5) / steps as f64);
        area.draw(&Rectangle::new([(x0, yb), (x1, ya)], c.filled()))?;
    }
    area.draw(&Rectangle::new([(x0, top), (x1, bottom)], MUTED.stroke_width(px(1))))?;
    // On a log scale, only whole powers of ten.
    let step = if scale.log {
        nice_step((scale.hi - scale.lo) / 6.0).max(1.0)
    } else {
        nice_step((scale.hi - scale.lo) / 6.0)
    };
    let first = (scale.lo / step).ceil() as i64;
    let last = (scale.hi / step).floor() as i64;
    let text = text_style(16, &INK, (HPos::Left, VPos::Center));
    for k in first..=last.min(first + 20) {
        let v = k as f64 * step;
        let y = bottom - (height * (v - scale.lo) / (scale.hi - scale.lo)).round() as i32;
        area.draw(&PathElement::new(vec![(x1, y), (x1 + pos(6), y)], INK.stroke_width(px(1))))?;
        let mut label = tick(v);
        if scale.log {
            label = format!("10{}", superscript(&label));
        }
        area.draw_text(&label, &text, (x1 + pos(10), y))?;
    }
    let note = text_style(14, &MUTED, (HPos::Left, VPos::Center));
    if scale.clipped_hi {
        area.draw_text("and above", &note, (x0, top - pos(14)))?;
    }
    if scale.clipped_lo {
        area.draw_text("and below", &note, (x0, bottom + pos(14)))?;
    }
    // The bar's caption, rotated along it.
    let caption = TextStyle::from((FONT, px(18)).into_font().transform(FontTransform::Rotate270))
        .color(&INK)
        .pos(Pos::new(HPos::Center, VPos::Center));
    area.draw_text(label, &caption, (pos(146), (top + bottom) / 2))?;
    Ok(())
}

/// A tick label with a true minus sign and no trailing zeros.
fn tick(v: f64) -> String {
    let v = if v.abs() < 1e-12 { 0.0 } else { v };
    let text = format!("{v:.3}");
    let text = if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.') } else { &text };
    text.replace('-', "−")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_ticks() {
        assert_eq!(viridis(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(viridis(1.0), RGBColor(0xfd, 0xe7, 0x25));
        assert_eq!(tick(-1.5), "−1.5");
        assert_eq!(tick(2.0), "2");
        assert_eq!(column_of("a'"), "final_a'");
        assert_eq!(superscript("−11"), "⁻¹¹");
        assert_eq!(column_of("drift"), "energy_drift");
        let s = Scale::new(&[-12.0, -10.0, f32::NAN], true);
        assert_eq!(s.fraction(-12.0), Some(0.0));
        assert_eq!(s.fraction(f32::NAN), None);
    }

    /// A 3 × 2 sweep of a pendulum, as `lagrange sweep` writes it; the last run failed.
    const SWEEP: &str = "\
# lagrange sweep; model=planar pendulum; grid=ph=0.1:1.0:3,ph'=0.0:1.0:2; runs=6; until=1.0; method=taylor; rtol=1e-10; atol=1e-12; parameters=m=1.0 l=1.0 g=9.81; lyapunov=d0 1e-8 every 1.0
run,ph,ph',t_final,final_ph,final_ph',energy_drift,lyapunov,failure
0,0.1,0.0,1.0,-0.0999934383401109,-0.0035849840375417018,7.279411955722609e-16,0.022172785392801885,
1,0.1,1.0,1.0,-0.08978841133859768,-1.0094471658261608,2.800435746395526e-14,0.0443541636596117,
2,0.55,0.0,1.0,-0.5487218108104958,-0.11443041862337466,7.752596657617844e-14,0.2562022880062934,
3,0.55,1.0,1.0,-0.5184136485490644,-1.1469632760590738,1.1216220078986836e-13,0.28641924955143216,
4,1.0,0.0,1.0,-0.9800669929332254,-0.5718037207195228,2.9056512135391636e-13,0.6261815773309477,
5,1.0,1.0,0.5,NaN,NaN,NaN,NaN,step size underflow
";

    fn table() -> mech::SweepTable {
        mech::SweepTable::parse(SWEEP, "sweep.csv").expect("the sweep's CSV reads back")
    }

    #[test]
    fn a_map_of_a_sweep() {
        let table = table();
        let mut map = HeatMap::new(&table.header, "lyapunov").unwrap();
        table.rows.iter().for_each(|row| map.add(row));
        let svg = map.svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "not an SVG: {}", &svg[..80]);
        crate::plot::tests::assert_balanced(&svg);
        for text in ["planar pendulum: largest Lyapunov exponent λ", "3 × 2 runs to t = 1, taylor", "grey: 1 failed"]
        {
            assert!(svg.contains(text), "the map lacks {text:?}");
        }
        let drift = HeatMap::new(&table.header, "drift").unwrap().svg().unwrap();
        assert!(drift.contains("relative drift of H") && drift.contains("grey: 6 failed or missing"));
    }

    #[test]
    fn maps_that_cannot_be_drawn() {
        let table = table();
        let unknown = HeatMap::new(&table.header, "x").err();
        let known = ["lyapunov", "drift", "ph", "ph'"].map(String::from).to_vec();
        assert_eq!(unknown, Some(HeatMapError::UnknownColor { color: "x".into(), known }));
        let line = SWEEP.replace("grid=ph=0.1:1.0:3,ph'=0.0:1.0:2", "grid=ph=0.1:1.0:6");
        let one_axis = mech::SweepTable::parse(&line, "sweep.csv").unwrap();
        let err = HeatMap::new(&one_axis.header, "lyapunov").err();
        assert_eq!(err, Some(HeatMapError::NotTwoDimensional { axes: 1 }));
        let huge =
            SWEEP.replace("grid=ph=0.1:1.0:3,ph'=0.0:1.0:2; runs=6", "grid=ph=0:1:2000,ph'=0:1:1000; runs=2000000");
        let huge = mech::SweepTable::parse(&huge, "sweep.csv").map(|t| HeatMap::new(&t.header, "lyapunov").err());
        assert_eq!(huge.ok().flatten(), Some(HeatMapError::TooManyCells { first: 2000, second: 1000 }));
    }
}
