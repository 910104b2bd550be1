//! YUV4MPEG2 (`.y4m`) video: a streaming reader and writer of 8-bit RGB frames.
//!
//! Reader: 8-bit `C420jpeg`, `C420paldv`, `C420mpeg2`, `C420`, `C422`, `C444` and `Cmono`
//! (the default is 4:2:0). Chroma is upsampled by taking the chroma sample covering each
//! pixel (siting differences are below a pixel and ignored). YCbCr to RGB uses BT.601;
//! limited ("TV") range unless the header says `XCOLORRANGE=FULL`.
//! Writer: `C444 XCOLORRANGE=FULL` (BT.601 full range), the least lossy 8-bit form; ffmpeg reads it.
//!
//! A stream that ends inside a frame is an error naming the frame; one that ends between frames
//! is the end of the video.

use crate::{IoError, Result};
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use std::io::{BufRead, Read, Write};
use std::path::{Path, PathBuf};

/// Chroma subsampling of a stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chroma {
    /// 4:2:0 (half width, half height).
    C420,
    /// 4:2:2 (half width).
    C422,
    /// 4:4:4.
    C444,
    /// Luma only.
    Mono,
}

/// What the stream header says.
#[derive(Clone, Debug, PartialEq)]
pub struct Y4mHeader {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Frame rate as a fraction (numerator, denominator); (0, 0) when unknown.
    pub fps: (u32, u32),
    /// Chroma subsampling.
    pub chroma: Chroma,
    /// Full-range (`XCOLORRANGE=FULL`) rather than limited-range samples.
    pub full_range: bool,
}

impl Y4mHeader {
    fn plane_sizes(&self) -> (usize, usize) {
        let (w, h) = (self.width, self.height);
        let c = match self.chroma {
            Chroma::C420 => w.div_ceil(2) * h.div_ceil(2),
            Chroma::C422 => w.div_ceil(2) * h,
            Chroma::C444 => w * h,
            Chroma::Mono => 0,
        };
        (w * h, c)
    }

    /// Bytes of one frame's samples (without the `FRAME` line).
    pub fn frame_bytes(&self) -> usize {
        let (y, c) = self.plane_sizes();
        y + 2 * c
    }
}

/// Longest header or `FRAME` line accepted (guards against reading a non-Y4M file whole).
const MAX_LINE: usize = 4096;

/// Reads one line (without '\n'); `Ok(None)` at a clean end of stream.
fn read_line<R: BufRead>(r: &mut R, path: &Path, what: &str) -> Result<Option<Vec<u8>>> {
    let mut line = Vec::new();
    let n = std::io::Read::take(r, MAX_LINE as u64)
        .read_until(b'\n', &mut line)
        .map_err(|e| IoError::Io { path: path.into(), source: e })?;
    if n == 0 {
        return Ok(None);
    }
    if line.last() != Some(&b'\n') {
        return Err(IoError::Corrupt { path: path.into(), reason: format!("{what} line is cut or too long") });
    }
    line.pop();
    Ok(Some(line))
}

fn parse_header(line: &[u8], path: &Path) -> Result<Y4mHeader> {
    let bad = |reason: String| IoError::Corrupt { path: path.into(), reason };
    // ASCII, not just UTF-8: tags are split after their first byte (found by fuzzing).
    let text =
        std::str::from_utf8(line).ok().filter(|t| t.is_ascii()).ok_or_else(|| bad("header is not ASCII".into()))?;
    let mut tokens = text.split(' ').filter(|t| !t.is_empty());
    if tokens.next() != Some("YUV4MPEG2") {
        return Err(bad("not a YUV4MPEG2 stream".into()));
    }
    let mut h = Y4mHeader { width: 0, height: 0, fps: (0, 0), chroma: Chroma::C420, full_range: false };
    for t in tokens {
        let (tag, val) = t.split_at(1);
        match tag {
            "W" => h.width = val.parse().map_err(|_| bad(format!("bad width '{val}'")))?,
            "H" => h.height = val.parse().map_err(|_| bad(format!("bad height '{val}'")))?,
            "F" => {
                let (n, d) = val.split_once(':').ok_or_else(|| bad(format!("bad frame rate '{val}'")))?;
                h.fps = (n.parse().unwrap_or(0), d.parse().unwrap_or(0));
            }
            "C" => {
                h.chroma = match val {
                    "420jpeg" | "420paldv" | "420mpeg2" | "420" => Chroma::C420,
                    "422" => Chroma::C422,
                    "444" => Chroma::C444,
                    "mono" => Chroma::Mono,
                    other => {
                        return Err(IoError::Invalid {
                            path: path.into(),
                            reason: format!(
                                "unsupported Y4M colour space C{other} (ocellus reads 8-bit 420, 422, 444, mono)"
                            ),
                        })
                    }
                }
            }
            "X" if val.eq_ignore_ascii_case("COLORRANGE=FULL") => h.full_range = true,
            _ => {} // interlacing, aspect ratio, comments: not needed for RGB frames
        }
    }
    if h.width == 0 || h.height == 0 || h.width > 1 << 15 || h.height > 1 << 15 || h.width * h.height > 1 << 26 {
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!("frame size {}x{} is outside 1..=32768 per side and 67 megapixels", h.width, h.height),
        });
    }
    Ok(h)
}

/// BT.601 YCbCr (8-bit) to RGB in [0, 255].
#[inline]
fn ycbcr_to_rgb(y: u8, cb: u8, cr: u8, full: bool) -> [u8; 3] {
    let (y, cb, cr) = if full {
        (y as f32, cb as f32 - 128.0, cr as f32 - 128.0)
    } else {
        (
            (y as f32 - 16.0) * (255.0 / 219.0),
            (cb as f32 - 128.0) * (255.0 / 224.0),
            (cr as f32 - 128.0) * (255.0 / 224.0),
        )
    };
    let r = y + 1.402 * cr;
    let b = y + 1.772 * cb;
    let g = (y - 0.299 * r - 0.114 * b) / 0.587;
    [r, g, b].map(|v| v.round().clamp(0.0, 255.0) as u8)
}

/// BT.601 full-range RGB to YCbCr.
#[inline]
fn rgb_to_ycbcr(p: [u8; 3]) -> [u8; 3] {
    let [r, g, b] = p.map(|v| v as f32);
    let y = 0.299 * r + 0.587 * g + 0.114 * b;
    let cb = 128.0 + (b - y) / 1.772;
    let cr = 128.0 + (r - y) / 1.402;
    [y, cb, cr].map(|v| v.round().clamp(0.0, 255.0) as u8)
}

/// Streaming reader: one frame in memory at a time.
#[derive(Debug)]
pub struct Y4mReader<R> {
    input: R,
    path: PathBuf,
    header: Y4mHeader,
    buf: Vec<u8>,
    frame: usize,
}

impl<R: BufRead> Y4mReader<R> {
    /// Reads the stream header; `path` names the source in errors.
    pub fn new(mut input: R, path: &Path) -> Result<Self> {
        let line = read_line(&mut input, path, "header")?.ok_or_else(|| IoError::EmptyFile { path: path.into() })?;
        let header = parse_header(&line, path)?;
        Ok(Self { input, path: path.into(), buf: Vec::new(), header, frame: 0 })
    }

    /// The stream header.
    pub fn header(&self) -> &Y4mHeader {
        &self.header
    }

    /// Frames read so far.
    pub fn frames_read(&self) -> usize {
        self.frame
    }

    fn video_error(&self, reason: String) -> IoError {
        IoError::Video { path: self.path.clone(), frame: self.frame, reason }
    }

    /// The next frame, or `None` at the end of the stream.
    pub fn next_frame(&mut self) -> Result<Option<RgbImage>> {
        let line = match read_line(&mut self.input, &self.path, "FRAME") {
            Ok(Some(l)) => l,
            Ok(None) => return Ok(None),
            Err(e) => return Err(self.video_error(e.to_string())),
        };
        if !line.starts_with(b"FRAME") {
            return Err(self.video_error("expected a FRAME marker".into()));
        }
        // Read up to the frame's size: the buffer grows with the data actually present, so a
        // header that promises huge frames cannot make us allocate them.
        let n = self.header.frame_bytes();
        self.buf.clear();
        let read = (&mut self.input).take(n as u64).read_to_end(&mut self.buf);
        if let Err(e) = read {
            return Err(self.video_error(e.to_string()));
        }
        if self.buf.len() < n {
            return Err(self.video_error(format!("truncated: {} of {n} bytes", self.buf.len())));
        }
        let img = self.to_rgb();
        self.frame += 1;
        Ok(Some(img))
    }

    fn to_rgb(&self) -> RgbImage {
        let h = &self.header;
        let (w, ht) = (h.width, h.height);
        let (ny, nc) = h.plane_sizes();
        let (luma, cb, cr) = (&self.buf[..ny], &self.buf[ny..ny + nc], &self.buf[ny + nc..ny + 2 * nc]);
        let cw = match h.chroma {
            Chroma::C444 => w,
            _ => w.div_ceil(2),
        };
        let full = h.full_range;
        RgbImage::U8(Plane::from_fn(w, ht, |x, y| {
            let l = luma[y * w + x];
            let ci = match h.chroma {
                Chroma::C420 => (y / 2) * cw + x / 2,
                Chroma::C422 => y * cw + x / 2,
                Chroma::C444 => y * w + x,
                Chroma::Mono => return ycbcr_to_rgb(l, 128, 128, full),
            };
            ycbcr_to_rgb(l, cb[ci], cr[ci], full)
        }))
    }
}

/// Writes RGB frames as `C444 XCOLORRANGE=FULL` YUV4MPEG2.
#[derive(Debug)]
pub struct Y4mWriter<W> {
    out: W,
    width: usize,
    height: usize,
    buf: Vec<u8>,
}

impl<W: Write> Y4mWriter<W> {
    /// Writes the header for `width` x `height` frames at `fps` = (numerator, denominator).
    pub fn new(mut out: W, width: usize, height: usize, fps: (u32, u32)) -> std::io::Result<Self> {
        writeln!(out, "YUV4MPEG2 W{width} H{height} F{}:{} Ip A1:1 C444 XCOLORRANGE=FULL", fps.0, fps.1)?;
        Ok(Self { out, width, height, buf: Vec::with_capacity(3 * width * height) })
    }

    /// Writes one frame; it must have the stream's size.
    pub fn write_frame(&mut self, frame: &RgbImage) -> std::io::Result<()> {
        if frame.size() != (self.width, self.height) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("frame is {:?}, stream is {}x{}", frame.size(), self.width, self.height),
            ));
        }
        let px = frame.to_u8();
        let n = self.width * self.height;
        self.buf.clear();
        self.buf.resize(3 * n, 0);
        for y in 0..self.height {
            for (x, &p) in px.row(y).iter().enumerate() {
                let [l, cb, cr] = rgb_to_ycbcr(p);
                let i = y * self.width + x;
                self.buf[i] = l;
                self.buf[n + i] = cb;
                self.buf[2 * n + i] = cr;
            }
        }
        self.out.write_all(b"FRAME\n")?;
        self.out.write_all(&self.buf)
    }

    /// Flushes and returns the output.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(k: u8) -> RgbImage {
        RgbImage::U8(Plane::from_fn(6, 4, |x, y| [(x * 40) as u8 + k, (y * 60) as u8, 200 - k]))
    }

    #[test]
    fn round_trip_is_within_one_level() {
        let mut w = Y4mWriter::new(Vec::new(), 6, 4, (25, 1)).unwrap();
        for k in 0..3 {
            w.write_frame(&frame(k)).unwrap();
        }
        let bytes = w.finish().unwrap();
        let mut r = Y4mReader::new(&bytes[..], Path::new("t.y4m")).unwrap();
        assert_eq!(r.header().fps, (25, 1));
        for k in 0..3 {
            let got = r.next_frame().unwrap().unwrap().to_u8();
            let want = frame(k).to_u8();
            for (a, b) in got.to_vec().iter().zip(want.to_vec()) {
                for c in 0..3 {
                    assert!((a[c] as i32 - b[c] as i32).abs() <= 1, "{a:?} vs {b:?}");
                }
            }
        }
        assert!(r.next_frame().unwrap().is_none());
    }

    #[test]
    fn limited_range_420_grey_and_truncation() {
        // 4x2 frame, 4:2:0, limited range: luma 16 is black, 235 white, chroma neutral.
        let mut s = b"YUV4MPEG2 W4 H2 F30:1 C420jpeg\nFRAME\n".to_vec();
        s.extend([16, 235, 16, 235, 126, 126, 126, 126]);
        s.extend([128, 128, 128, 128]);
        let mut r = Y4mReader::new(&s[..], Path::new("t.y4m")).unwrap();
        let f = r.next_frame().unwrap().unwrap().to_u8();
        assert_eq!((f.get(0, 0), f.get(1, 0), f.get(0, 1)), ([0, 0, 0], [255, 255, 255], [128, 128, 128]));
        // A second frame cut short: an error that names frame 1.
        s.extend(b"FRAME\n");
        s.extend([1, 2, 3]);
        let mut r = Y4mReader::new(&s[..], Path::new("t.y4m")).unwrap();
        assert!(r.next_frame().unwrap().is_some());
        let e = r.next_frame().unwrap_err().to_string();
        assert!(e.contains("frame 1") && e.contains("truncated"), "{e}");
    }

    #[test]
    fn bad_headers_are_errors() {
        for s in [
            &b""[..],
            b"P6\n",
            b"YUV4MPEG2 W0 H2\n",
            b"YUV4MPEG2 W4 H2 C420p10\n",
            b"YUV4MPEG2 W4 H2",
            "YUV4MPEG2 W4 H2 \u{37a}4\n".as_bytes(),
        ] {
            assert!(Y4mReader::new(s, Path::new("t.y4m")).is_err(), "{:?}", String::from_utf8_lossy(s));
        }
        let s = b"YUV4MPEG2 W2 H2 C444\nFROG\n".to_vec();
        assert!(Y4mReader::new(&s[..], Path::new("t.y4m")).unwrap().next_frame().is_err());
    }
}
