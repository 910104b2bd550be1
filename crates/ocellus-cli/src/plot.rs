//! Line plots (PNG), with the embedded DejaVu Sans Mono font.

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

/// One line: a label and its (x, y) points.
pub struct Series<'a> {
    pub label: &'a str,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
}

/// A plot of lines.
pub struct Plot<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: &'a [Series<'a>],
    /// A dashed horizontal line (value, label).
    pub threshold: Option<(f64, &'a str)>,
    /// The vertical range; default from 0 (or the data's minimum) to 1.1 x the maximum.
    pub y_range: Option<(f64, f64)>,
}

/// Writes `plot` as a 960x480 PNG.
pub fn draw(path: &Path, plot: &Plot) -> Result<()> {
    register_font();
    let (w, h) = (960u32, 480u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    render(&mut buf, (w, h), plot).map_err(|e| anyhow!("plot {}: {e}", path.display()))?;
    let img = ocellus_image::Plane::from_vec(
        w as usize,
        h as usize,
        buf.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    )?;
    ocellus_io::write_png(path, &img)?;
    Ok(())
}

fn render(buf: &mut [u8], size: (u32, u32), p: &Plot) -> std::result::Result<(), String> {
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let xs = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)).filter(|v| v.is_finite());
    let (x_min, x_max) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let (x_min, x_max) = if x_min < x_max { (x_min, x_max) } else { (0.0, 1.0) };
    let (y_min, y_max) = p.y_range.unwrap_or_else(|| {
        let ys = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)).chain(p.threshold.map(|t| t.0));
        let (lo, hi) = ys.filter(|v| v.is_finite()).fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        (lo * 1.1, (hi * 1.1).max(lo + 1e-3))
    });
    let mut chart = ChartBuilder::on(&root)
        .caption(p.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x_min..x_max, y_min..y_max)
        .map_err(|x| e(&x))?;
    chart.configure_mesh().x_desc(p.x_label).y_desc(p.y_label).draw().map_err(|x| e(&x))?;
    for s in p.series {
        let color = s.color;
        chart
            .draw_series(LineSeries::new(s.points.iter().copied().filter(|q| q.1.is_finite()), color.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(s.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        chart
            .draw_series(s.points.iter().filter(|q| q.1.is_finite()).map(|&q| Circle::new(q, 3, color.filled())))
            .map_err(|x| e(&x))?;
    }
    if let Some((t, label)) = p.threshold {
        let n = 100;
        let dash = (x_max - x_min) / n as f64;
        let dashes = (0..n).step_by(2).map(|i| {
            let x0 = x_min + i as f64 * dash;
            PathElement::new(vec![(x0, t), (x0 + dash, t)], BLACK.stroke_width(1))
        });
        chart
            .draw_series(dashes)
            .map_err(|x| e(&x))?
            .label(label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}
