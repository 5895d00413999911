//! The figure of a Poincaré section (what `simulate --section --plot` and
//! `sweep --section --plot` draw): the points where runs crossed a surface, in
//! the plane of two quantities, a colour per run.
//!
//! A section of a long run has tens of thousands of points, many of them on
//! the same pixel: points closer than a quarter of a figure pixel to one drawn
//! before in the same colour are left out, so the file stays small whatever
//! the run's length, and the figure shows what it would show with them.

use super::*;

/// The points of one run.
pub struct SectionSet {
    /// The run, as the legend names it (`y' = 0.1`), or empty for a single run.
    pub label: String,
    /// The points (x, y); non-finite ones are skipped.
    pub points: Vec<[f64; 2]>,
}

/// Everything [`section_svg`] draws.
pub struct SectionPlot {
    /// The figure's title, normally the model's name.
    pub title: String,
    /// The line under the title: the surface, the method, the number of points.
    pub subtitle: String,
    /// The names of the plane's axes (x, then y).
    pub axes: [String; 2],
    /// The runs' points.
    pub sets: Vec<SectionSet>,
}

/// The figure's subtitle for `points` points of `section` in the run `report`:
/// the surface and the way it is crossed, the count, the method.
pub fn section_subtitle(section: &mech::Section, points: usize, report: &mech::RunReport) -> String {
    let condition = section.condition();
    format!(
        "section {} ({}), {} point{}, {} rtol {}",
        condition.text,
        if condition.direction == num::Direction::Falling { "decreasing" } else { "increasing" },
        points,
        if points == 1 { "" } else { "s" },
        report.method.name(),
        num::Shortest(report.rtol)
    )
}

const SECTION_WIDTH: u32 = 1000;
const SECTION_HEIGHT: u32 = 860;
/// Sub-pixel cells per figure pixel in which one point per set is drawn.
const CELLS_PER_PIXEL: f64 = 4.0;

/// The section as SVG text.
pub fn section_svg(data: &SectionPlot) -> Result<String, DrawError> {
    Ok(render_section(data)?)
}

fn render_section(data: &SectionPlot) -> Result<String, Box<dyn Error>> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (px(SECTION_WIDTH), px(SECTION_HEIGHT))).into_drawing_area();
        root.fill(&WHITE)?;
        let (header, body) = root.split_vertically(px(96));
        let center = header.dim_in_pixel().0 as i32 / 2;
        header.draw_text(&shorten(&data.title, 60), &bold_style(38, (HPos::Center, VPos::Top)), (center, pos(16)))?;
        header.draw_text(
            &shorten(&data.subtitle, 100),
            &text_style(22, &MUTED, (HPos::Center, VPos::Top)),
            (center, pos(60)),
        )?;
        let body = body.margin(0, px(10), px(10), px(14));
        let labelled = data.sets.len() > 1 && data.sets.iter().any(|s| !s.label.is_empty());
        if labelled {
            let (chart_area, legend_area) = body.split_horizontally(body.dim_in_pixel().0 - px(170));
            draw_points(&chart_area, data)?;
            let entries: Vec<(String, RGBColor)> =
                data.sets.iter().take(MAX_SERIES).enumerate().map(|(k, set)| (set.label.clone(), PALETTE[k])).collect();
            draw_legend(&legend_area, &entries, data.sets.len())?;
        } else {
            draw_points(&body, data)?;
        }
        root.present()?;
    }
    let big = format!("width=\"{}\" height=\"{}\"", px(SECTION_WIDTH), px(SECTION_HEIGHT));
    Ok(svg.replacen(&big, &format!("width=\"{SECTION_WIDTH}\" height=\"{SECTION_HEIGHT}\""), 1))
}

fn finite(p: &&[f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// The chart of the points, each set in its colour (the palette's, in turn).
fn draw_points(area: &Area, data: &SectionPlot) -> DrawResult {
    let all = || data.sets.iter().flat_map(|s| s.points.iter().filter(finite));
    if all().next().is_none() {
        return draw_message(area, "Section", "no crossings");
    }
    let xs: Vec<f64> = all().map(|p| p[0]).collect();
    let ys: Vec<f64> = all().map(|p| p[1]).collect();
    let (x_axis, y_axis) = (Axis::of(&xs, 6), Axis::of(&ys, 6));
    let y_label = |value: &f64| format_tick(*value, y_axis.step);
    let mut chart = build_chart(area, "Section", &x_axis, &y_axis, &y_label, 0)?;
    configure_mesh(&mut chart, &x_axis, &data.axes[0], &data.axes[1], &y_label)?;
    let (width, height) = chart.plotting_area().dim_in_pixel();
    // The sub-pixel cell of a value along an axis drawn over `pixels` (at SCALE).
    let cell = |v: f64, axis: &Axis, pixels: u32| {
        ((v - axis.lo) / (axis.hi - axis.lo) * f64::from(pixels) / f64::from(SCALE) * CELLS_PER_PIXEL).floor() as i64
    };
    for (k, set) in data.sets.iter().enumerate() {
        let color = PALETTE[k % MAX_SERIES];
        let mut seen = std::collections::HashSet::new();
        let dots = set
            .points
            .iter()
            .filter(finite)
            .filter(|p| seen.insert((cell(p[0], &x_axis, width), cell(p[1], &y_axis, height))))
            .map(|p| Circle::new((p[0], p[1]), px(1), color.filled()));
        chart.draw_series(dots)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64) -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| (k as f64 * 0.618_033_988_7 * std::f64::consts::TAU).sin_cos())
            .map(|(s, c)| [r * c, r * s])
            .collect()
    }

    #[test]
    fn points_on_one_pixel_are_drawn_once() {
        let plot = |n| SectionPlot {
            title: "test".into(),
            subtitle: "x = 0".into(),
            axes: ["y".into(), "p_y".into()],
            sets: vec![
                SectionSet { label: "a".into(), points: circle(n, 1.0) },
                SectionSet { label: "b".into(), points: circle(n, 0.5) },
            ],
        };
        let small = section_svg(&plot(2_000)).unwrap();
        let large = section_svg(&plot(200_000)).unwrap();
        crate::plot::tests::assert_balanced(&large);
        let dots = |svg: &str| svg.matches("<circle").count();
        assert!(dots(&small) > 3_000, "{}", dots(&small));
        // Two circles of a few thousand figure pixels' length: bounded by the pixels, not the points.
        assert!(dots(&large) < 40_000, "{}", dots(&large));
        assert!(large.contains("p_y") && !large.contains("first "));
    }

    #[test]
    fn no_points_is_a_message_not_an_error() {
        let plot = SectionPlot {
            title: "t".into(),
            subtitle: String::new(),
            axes: ["y".into(), "p_y".into()],
            sets: vec![SectionSet { label: String::new(), points: vec![[f64::NAN, 1.0]] }],
        };
        assert!(section_svg(&plot).unwrap().contains("no crossings"));
    }
}
