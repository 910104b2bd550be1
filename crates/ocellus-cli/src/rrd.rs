//! `--rrd FILE` of `attend`, `odometry` and `track`: the run logged over time for the Rerun
//! viewer (<https://rerun.io>; `rerun FILE` opens it), when ocellus is built with the `rerun`
//! feature (`cargo build --release --features rerun`). Without the feature the option is
//! still accepted by the parser and refused with that advice, so scripts fail loudly rather
//! than run without their log.
//!
//! Conventions of the log:
//! - timelines: `frame` (the frame index) and, where the command knows it, `time` (seconds);
//! - 2D entities are in the frame's pixels with Rerun's convention (the first pixel's centre
//!   at (0.5, 0.5)); ocellus puts pixel centres at integers, so 0.5 is added here;
//! - 3D entities are in the command's world frame, metres (for `track`, the camera's: x right,
//!   y down, z forward; for `odometry`, the floor's, z up out of it);
//! - frames are logged JPEG-encoded (quality 85), maps as 32-bit float grey images at their
//!   own size.

use anyhow::Result;
use ocellus_image::Plane;
use std::path::Path;

/// A 2D point's colour, RGBA.
pub type Rgba = [u8; 4];

/// An open log; every method logs at the time set by [`Recorder::at`].
#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
pub struct Recorder {
    #[cfg(feature = "rerun")]
    rec: rerun::RecordingStream,
}

/// Opens `path` for the log of the application `app` (e.g. `ocellus_attend`; `None`: no log).
pub fn open(path: Option<&Path>, app: &'static str) -> Result<Option<Recorder>> {
    let Some(path) = path else { return Ok(None) };
    open_file(path, app).map(Some)
}

#[cfg(not(feature = "rerun"))]
fn open_file(path: &Path, _app: &'static str) -> Result<Recorder> {
    anyhow::bail!(
        "--rrd {}: this ocellus was built without the rerun feature; build it with \
         `cargo build --release --features rerun`",
        path.display()
    )
}

#[cfg(feature = "rerun")]
fn open_file(path: &Path, app: &'static str) -> Result<Recorder> {
    use anyhow::Context;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::output_files::create_dir(dir)?;
    }
    // Enabled whatever the RERUN environment variable says: the user asked for this file.
    let rec = rerun::RecordingStreamBuilder::new(app)
        .enabled(true)
        .save(path)
        .with_context(|| format!("cannot write the Rerun log {}", path.display()))?;
    Ok(Recorder { rec })
}

/// An ocellus pixel position (centres at integers) in Rerun's frame (centres at half-integers).
#[cfg(feature = "rerun")]
fn frame_px(p: [f64; 2]) -> [f32; 2] {
    [p[0] as f32 + 0.5, p[1] as f32 + 0.5]
}

#[cfg(feature = "rerun")]
fn colour_of(c: Rgba) -> rerun::Color {
    rerun::Color::from_unmultiplied_rgba(c[0], c[1], c[2], c[3])
}

#[cfg(feature = "rerun")]
impl Recorder {
    /// Sets the time of what follows: frame `frame`, and `time_s` seconds when known.
    pub fn at(&self, frame: usize, time_s: Option<f64>) {
        self.rec.set_time_sequence("frame", frame as i64);
        if let Some(t) = time_s {
            self.rec.set_duration_secs("time", t);
        }
    }

    fn log(&self, entity: &str, what: &impl rerun::AsComponents) -> Result<()> {
        Ok(self.rec.log(entity, what)?)
    }

    fn log_static(&self, entity: &str, what: &impl rerun::AsComponents) -> Result<()> {
        Ok(self.rec.log_static(entity, what)?)
    }

    /// An RGB frame, JPEG-encoded.
    pub fn frame_rgb(&self, entity: &str, img: &Plane<[u8; 3]>) -> Result<()> {
        let (w, h) = img.size();
        let raw: Vec<u8> = (0..h).flat_map(|y| img.row(y).iter().flatten().copied()).collect();
        self.jpeg(entity, &raw, w, h, image::ExtendedColorType::Rgb8)
    }

    /// A grey frame, JPEG-encoded.
    pub fn frame_grey(&self, entity: &str, img: &Plane<u8>) -> Result<()> {
        let (w, h) = img.size();
        let raw: Vec<u8> = (0..h).flat_map(|y| img.row(y).iter().copied()).collect();
        self.jpeg(entity, &raw, w, h, image::ExtendedColorType::L8)
    }

    fn jpeg(&self, entity: &str, raw: &[u8], w: usize, h: usize, kind: image::ExtendedColorType) -> Result<()> {
        use image::ImageEncoder;
        let mut bytes = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 85).write_image(
            raw,
            u32::try_from(w)?,
            u32::try_from(h)?,
            kind,
        )?;
        self.log(entity, &rerun::EncodedImage::from_file_contents(bytes))
    }

    /// A map (saliency, surprise, ...) as a float grey image at its own size.
    pub fn map(&self, entity: &str, map: &Plane<f32>) -> Result<()> {
        let (w, h) = map.size();
        let v: Vec<f32> = (0..h).flat_map(|y| map.row(y).iter().copied()).collect();
        let img = rerun::Image::from_elements(&v, [u32::try_from(w)?, u32::try_from(h)?], rerun::ColorModel::L);
        self.log(entity, &img)
    }

    /// One value of a time series.
    pub fn scalar(&self, entity: &str, v: f64) -> Result<()> {
        if !v.is_finite() {
            return Ok(());
        }
        self.log(entity, &rerun::Scalars::single(v))
    }

    /// Points in the frame (ocellus pixel coordinates), radius in pixels.
    pub fn points_2d(&self, entity: &str, pts: &[[f64; 2]], radius_px: f32, colour: Rgba) -> Result<()> {
        let p: Vec<[f32; 2]> = pts.iter().map(|&p| frame_px(p)).collect();
        self.log(
            entity,
            &rerun::Points2D::new(p)
                .with_radii([rerun::Radius::new_ui_points(radius_px)])
                .with_colors([colour_of(colour)]),
        )
    }

    /// A polyline in the frame (ocellus pixel coordinates).
    pub fn strip_2d(&self, entity: &str, pts: &[[f64; 2]], colour: Rgba) -> Result<()> {
        let p: Vec<[f32; 2]> = pts.iter().map(|&p| frame_px(p)).collect();
        self.log(entity, &rerun::LineStrips2D::new([p]).with_colors([colour_of(colour)]))
    }

    /// Circles in the frame (ocellus pixel coordinates): `[x, y, r]`.
    pub fn circles_2d(&self, entity: &str, circles: &[[f64; 3]], colour: Rgba) -> Result<()> {
        let strips: Vec<Vec<[f32; 2]>> = circles
            .iter()
            .map(|c| {
                (0..=48)
                    .map(|i| {
                        let a = i as f64 / 48.0 * std::f64::consts::TAU;
                        frame_px([c[0] + c[2] * a.cos(), c[1] + c[2] * a.sin()])
                    })
                    .collect()
            })
            .collect();
        self.log(entity, &rerun::LineStrips2D::new(strips).with_colors([colour_of(colour)]))
    }

    /// Arrows in the frame from `origins` (ocellus pixel coordinates) along `vectors`, pixels.
    pub fn arrows_2d(&self, entity: &str, origins: &[[f64; 2]], vectors: &[[f64; 2]], colour: Rgba) -> Result<()> {
        let o: Vec<[f32; 2]> = origins.iter().map(|&p| frame_px(p)).collect();
        let v: Vec<[f32; 2]> = vectors.iter().map(|p| [p[0] as f32, p[1] as f32]).collect();
        self.log(entity, &rerun::Arrows2D::from_vectors(v).with_origins(o).with_colors([colour_of(colour)]))
    }

    /// Points in 3D, metres; radius in metres.
    pub fn points_3d(&self, entity: &str, pts: &[[f64; 3]], radius_m: f32, colour: Rgba) -> Result<()> {
        let p: Vec<[f32; 3]> = pts.iter().map(|p| p.map(|v| v as f32)).collect();
        self.log(entity, &rerun::Points3D::new(p).with_radii([radius_m]).with_colors([colour_of(colour)]))
    }

    /// A polyline in 3D that holds for the whole recording (a full trajectory), metres.
    pub fn static_strip_3d(&self, entity: &str, pts: &[[f64; 3]], colour: Rgba) -> Result<()> {
        let p: Vec<[f32; 3]> = pts.iter().map(|p| p.map(|v| v as f32)).collect();
        self.log_static(entity, &rerun::LineStrips3D::new([p]).with_colors([colour_of(colour)]))
    }

    /// The axes of `entity`'s 3D space, for the whole recording: the camera's (x right, y
    /// down, z forward) or a floor's (x right, y forward, z up).
    pub fn static_axes(&self, entity: &str, camera: bool) -> Result<()> {
        let axes = if camera { rerun::ViewCoordinates::RDF() } else { rerun::ViewCoordinates::RFU() };
        self.log_static(entity, &axes)
    }

    /// Writes everything logged and closes the file.
    pub fn finish(self) -> Result<()> {
        self.rec.flush_blocking()?;
        Ok(())
    }
}

/// Without the feature a [`Recorder`] cannot be made ([`open`] refuses), so these are never
/// called; they keep the call sites free of `cfg`.
#[cfg(not(feature = "rerun"))]
#[allow(clippy::unused_self, missing_docs)]
impl Recorder {
    pub fn at(&self, _frame: usize, _time_s: Option<f64>) {}
    pub fn frame_rgb(&self, _e: &str, _img: &Plane<[u8; 3]>) -> Result<()> {
        Ok(())
    }
    pub fn frame_grey(&self, _e: &str, _img: &Plane<u8>) -> Result<()> {
        Ok(())
    }
    pub fn map(&self, _e: &str, _map: &Plane<f32>) -> Result<()> {
        Ok(())
    }
    pub fn scalar(&self, _e: &str, _v: f64) -> Result<()> {
        Ok(())
    }
    pub fn points_2d(&self, _e: &str, _p: &[[f64; 2]], _r: f32, _c: Rgba) -> Result<()> {
        Ok(())
    }
    pub fn strip_2d(&self, _e: &str, _p: &[[f64; 2]], _c: Rgba) -> Result<()> {
        Ok(())
    }
    pub fn circles_2d(&self, _e: &str, _c: &[[f64; 3]], _col: Rgba) -> Result<()> {
        Ok(())
    }
    pub fn arrows_2d(&self, _e: &str, _o: &[[f64; 2]], _v: &[[f64; 2]], _c: Rgba) -> Result<()> {
        Ok(())
    }
    pub fn points_3d(&self, _e: &str, _p: &[[f64; 3]], _r: f32, _c: Rgba) -> Result<()> {
        Ok(())
    }
    pub fn static_strip_3d(&self, _e: &str, _p: &[[f64; 3]], _c: Rgba) -> Result<()> {
        Ok(())
    }
    pub fn static_axes(&self, _e: &str, _camera: bool) -> Result<()> {
        Ok(())
    }
    pub fn finish(self) -> Result<()> {
        Ok(())
    }
}
