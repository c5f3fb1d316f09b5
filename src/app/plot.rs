//! Line plots as PNG (plotters on an in-memory bitmap, encoded with the png
//! crate), used by the sims' `--plot`. The font is vendored
//! (`assets/DejaVuSans.ttf`), so no system fontconfig is needed.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

static FONT: Once = Once::new();

fn register() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/DejaVuSans.ttf");
        // Registration fails only for a malformed font, which the vendored one is not.
        let _ = register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// The floor of the y axis as a fraction of the largest value.
pub const LOG_FLOOR: f64 = 1e-6;

/// The y range of a log axis over every finite value of `series`: from the
/// smallest positive value (at least [`LOG_FLOOR`] of the largest) to a
/// little above the largest.
fn log_range(series: &[(String, Vec<f64>)]) -> (f64, f64) {
    let values = || {
        series
            .iter()
            .flat_map(|s| s.1.iter().copied())
            .filter(|v| v.is_finite() && *v > 0.0)
    };
    let max = values().fold(0.0f64, f64::max);
    if max <= 0.0 {
        return (1e-3, 1.0);
    }
    let min = values().fold(max, f64::min).max(max * LOG_FLOOR);
    // Whole decades below and a margin above, so the lines clear the frame.
    (10f64.powf(min.log10().floor()), max * 1.5)
}

/// `y` drawn on a log axis whose floor is `floor`: non-finite or smaller
/// values sit on the floor.
fn floor_at(y: f64, floor: f64) -> f64 {
    if y.is_finite() { y.max(floor) } else { floor }
}

/// One chart of a [`line_plot_png`] figure: a title, the y axis' label and
/// its `(name, y values)` series, one value per step.
pub struct Panel<'a> {
    /// The chart's title.
    pub title: &'a str,
    /// The y axis' unit, e.g. `ms`.
    pub y_label: &'a str,
    /// One line per `(name, values)`.
    pub series: &'a [(String, Vec<f64>)],
}

/// Twelve distinct colours; a name keeps its colour in every panel.
const PALETTE: [RGBColor; 12] = [
    RGBColor(228, 26, 28),
    RGBColor(55, 126, 184),
    RGBColor(77, 175, 74),
    RGBColor(152, 78, 163),
    RGBColor(255, 127, 0),
    RGBColor(166, 86, 40),
    RGBColor(247, 129, 191),
    RGBColor(0, 0, 0),
    RGBColor(23, 190, 207),
    RGBColor(188, 189, 34),
    RGBColor(127, 127, 127),
    RGBColor(0, 0, 128),
];

/// Draws the panels one above the other, one line per series against the
/// step index, and writes a `width × height` PNG to `path`, titled `title`.
/// A series name has the same colour in every panel (the first panel's
/// order picks the colours).
///
/// The y axes are logarithmic: the sims' series can span four decades or
/// more (parry's TriMesh against cbvh's contact patches on a large scene,
/// a step in contact against one without), and on a linear axis the lower
/// lines would lie flat on zero. Values at or
/// below [`LOG_FLOOR`] of a panel's largest one (a step without contact
/// takes about nothing) are drawn at that floor, which the axis label
/// states.
pub fn line_plot_png(
    path: &Path,
    title: &str,
    panels: &[Panel<'_>],
    (width, height): (u32, u32),
) -> Result<(), String> {
    register();
    let mut names: Vec<&str> = Vec::new();
    for panel in panels {
        for (name, _) in panel.series {
            if !names.contains(&name.as_str()) {
                names.push(name);
            }
        }
    }
    let color_of = |name: &str| {
        let k = names.iter().position(|n| *n == name).unwrap_or(0);
        color_for(k, names.len())
    };
    let mut buf = vec![255u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, ("sans-serif", 22))
            .map_err(|e| e.to_string())?;
        let areas = root.split_evenly((panels.len().max(1), 1));
        for (panel, area) in panels.iter().zip(&areas) {
            draw_panel(area, panel, &color_of)?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let mut file = crate::files::AtomicFile::create(path).map_err(|e| err(&e))?;
    let mut enc = png::Encoder::new(&mut file, width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| err(&e))?;
    w.write_image_data(&buf).map_err(|e| err(&e))?;
    w.finish().map_err(|e| err(&e))?;
    file.commit().map_err(|e| err(&e))
}

/// The colour of series `k` of `n`: the palette's while it lasts, and
/// otherwise `n` hues spread around the colour wheel by the golden angle,
/// in two lightnesses, so that no two series of a plot share a colour.
fn color_for(k: usize, n: usize) -> RGBColor {
    if n <= PALETTE.len() {
        return PALETTE[k];
    }
    let hue = (k as f64 * 0.618_033_988_75).fract();
    let light = if k.is_multiple_of(2) { 0.38 } else { 0.55 };
    let c = HSLColor(hue, 0.85, light).to_rgba();
    RGBColor(c.0, c.1, c.2)
}

/// Width of the legend column right of each panel's plot, in pixels.
const LEGEND_WIDTH: u32 = 210;

/// One panel of [`line_plot_png`] on `area`: the plot, and right of it
/// (never over the lines) the legend.
fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    panel: &Panel<'_>,
    color_of: &dyn Fn(&str) -> RGBColor,
) -> Result<(), String> {
    let series = panel.series;
    let (w, _) = area.dim_in_pixel();
    let (area, legend) = area.split_horizontally(w.saturating_sub(LEGEND_WIDTH));
    let area = &area;
    let x_max = series.iter().map(|s| s.1.len()).max().unwrap_or(1).max(1);
    let (y_min, y_max) = log_range(series);
    let mut chart = ChartBuilder::on(area)
        .caption(panel.title, ("sans-serif", 17))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(70)
        .build_cartesian_2d(0usize..x_max, (y_min..y_max).log_scale())
        .map_err(|e| e.to_string())?;
    let y_desc = format!(
        "{} (log; ≤ {y_min:.0e} drawn at {y_min:.0e})",
        panel.y_label
    );
    chart
        .configure_mesh()
        .x_desc("step")
        .y_desc(y_desc)
        .draw()
        .map_err(|e| e.to_string())?;
    for (name, ys) in series {
        let color = color_of(name);
        chart
            .draw_series(LineSeries::new(
                ys.iter().enumerate().map(|(i, y)| (i, floor_at(*y, y_min))),
                color.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?;
    }
    // The legend in its own column, one row a series, in series order.
    for (k, (name, _)) in series.iter().enumerate() {
        let y = 40 + 17 * k as i32;
        let color = color_of(name);
        legend
            .draw(&PathElement::new(
                vec![(4, y), (28, y)],
                color.stroke_width(3),
            ))
            .map_err(|e| e.to_string())?;
        legend
            .draw(&Text::new(
                name.as_str(),
                (34, y - 7),
                ("sans-serif", 15).into_font(),
            ))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(ys: &[f64]) -> Vec<(String, Vec<f64>)> {
        vec![("a".into(), ys.to_vec())]
    }

    /// The log axis spans the smallest positive value (rounded down to a
    /// decade) to above the largest; zeros and NaN neither set it nor fall
    /// below it.
    #[test]
    fn the_log_axis_covers_every_value_and_floors_the_rest() {
        let (lo, hi) = log_range(&one(&[0.0, 0.35, 400.0, f64::NAN]));
        assert_eq!(lo, 0.1);
        assert!(hi > 400.0 && hi < 1000.0, "{hi}");
        // A value a billion times smaller than the largest is floored.
        let (lo, _) = log_range(&one(&[1e-9, 1000.0]));
        assert!((lo - 1e-3).abs() < 1e-12, "{lo}");
        assert_eq!(floor_at(0.0, lo), lo);
        assert_eq!(floor_at(f64::NAN, lo), lo);
        assert_eq!(floor_at(5.0, lo), 5.0);
        // Nothing positive: a default decade range, still a valid axis.
        assert_eq!(log_range(&one(&[0.0])), (1e-3, 1.0));
    }

    /// Every series of a plot has a colour of its own, however many there
    /// are (the sims draw 17 runs).
    #[test]
    fn every_series_has_its_own_colour() {
        for n in [3, 12, 13, 17, 30] {
            let colours: std::collections::HashSet<_> = (0..n)
                .map(|k| {
                    let c = color_for(k, n);
                    (c.0, c.1, c.2)
                })
                .collect();
            assert_eq!(colours.len(), n, "{n} series");
        }
    }

    /// A plot with zeros in it is written as a PNG of the asked size.
    #[test]
    fn a_plot_with_zero_steps_is_written() {
        let path = std::env::temp_dir().join(format!("cbvh-plot-{}.png", std::process::id()));
        let series = vec![
            ("parry".to_string(), vec![0.0, 400.0, 300.0]),
            ("plain".to_string(), vec![0.0, 0.3, 0.2]),
        ];
        let panels = [
            Panel {
                title: "narrow phase",
                y_label: "ms",
                series: &series,
            },
            Panel {
                title: "interference",
                y_label: "ms",
                series: &series[1..],
            },
        ];
        line_plot_png(&path, "t", &panels, (320, 400)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).ok();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (320, 400));
    }
}
