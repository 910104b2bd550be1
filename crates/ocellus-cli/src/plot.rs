//! Line plots of per-frame values (PNG), with the embedded DejaVu Sans Mono font.

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSansMono.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // A font that fails to load only costs the labels; the lines are still drawn.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One line: a label and its (frame, value) points.
pub struct Series<'a> {
    pub label: &'a str,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
}

/// Writes a plot of `series` against the frame index with a dashed horizontal line at
/// `threshold` (if any), `title` on top, `y_label` on the vertical axis.
pub fn line_plot(
    path: &Path,
    title: &str,
    y_label: &str,
    series: &[Series],
    threshold: Option<(f64, &str)>,
) -> Result<()> {
    register_font();
    let (w, h) = (960u32, 480u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    draw(&mut buf, (w, h), path, title, y_label, series, threshold)?;
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| anyhow!("plot buffer size"))?;
    ocellus_io::write_png(path, &img)?;
    Ok(())
}

fn draw(
    buf: &mut [u8],
    size: (u32, u32),
    path: &Path,
    title: &str,
    y_label: &str,
    series: &[Series],
    threshold: Option<(f64, &str)>,
) -> Result<()> {
    let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| anyhow!("plot {}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let x_max = series.iter().flat_map(|s| s.points.iter().map(|p| p.0)).fold(1.0f64, f64::max);
    let y_max = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(threshold.map(|t| t.0))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..x_max, 0f64..y_max)
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc("frame").y_desc(y_label).draw().map_err(|e| err(&e))?;
    for s in series {
        let color = s.color;
        chart
            .draw_series(LineSeries::new(s.points.iter().copied().filter(|p| p.1.is_finite()), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(s.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    if let Some((t, label)) = threshold {
        let dashes = (0..(x_max as usize * 2)).step_by(2).map(|i| {
            let x0 = i as f64 / 2.0;
            PathElement::new(vec![(x0, t), (x0 + 0.5, t)], BLACK.stroke_width(1))
        });
        chart
            .draw_series(dashes)
            .map_err(|e| err(&e))?
            .label(label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
