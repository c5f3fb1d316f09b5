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
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        // Registration fails only for a malformed font, which the vendored one is not.
        let _ = register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// Draws one line per `(name, y values)` series against the step index and
/// writes a `width × height` PNG to `path`.
pub fn line_plot_png(
    path: &Path,
    title: &str,
    y_label: &str,
    series: &[(String, Vec<f64>)],
    (width, height): (u32, u32),
) -> Result<(), String> {
    register();
    let mut buf = vec![255u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let x_max = series.iter().map(|s| s.1.len()).max().unwrap_or(1).max(1);
        let y_max = series
            .iter()
            .flat_map(|s| s.1.iter().copied())
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max)
            .max(1e-6)
            * 1.05;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0usize..x_max, 0f64..y_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("step")
            .y_desc(y_label)
            .draw()
            .map_err(|e| e.to_string())?;
        // Twelve distinct colours (the sims draw up to seven runs and their
        // interference series), so no two series share one.
        let palette = [
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
        for (k, (name, ys)) in series.iter().enumerate() {
            let color = palette[k % palette.len()];
            chart
                .draw_series(LineSeries::new(
                    ys.iter().enumerate().map(|(i, y)| (i, *y)),
                    color.stroke_width(2),
                ))
                .map_err(|e| e.to_string())?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc
        .write_header()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    w.write_image_data(&buf)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}
