//! Frame sources: a folder of images, a Y4M file, or any video ffmpeg can read, streamed one
//! frame at a time (memory does not grow with the length of the video).
//!
//! Video files other than `.y4m` are decoded by running the `ffmpeg` program as a subprocess
//! (`ffprobe` for the size and frame count, `ffmpeg ... -f rawvideo -pix_fmt rgb24 -` for the
//! frames); nothing links to libav. All frames of a source must have the same size.

use crate::y4m::Y4mReader;
use crate::{read_image_within, IoError, Result, DEFAULT_MAX_PIXELS};
use ocellus_image::convert::RgbImage;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};

/// Compares file names with runs of digits as numbers ("frame2" < "frame10").
pub fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    let (mut ai, mut bi) = (a.chars().peekable(), b.chars().peekable());
    loop {
        match (ai.peek().copied(), bi.peek().copied()) {
            (None, None) => return std::cmp::Ordering::Equal,
            (None, _) => return std::cmp::Ordering::Less,
            (_, None) => return std::cmp::Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let take = |it: &mut std::iter::Peekable<std::str::Chars>| {
                    let mut s = String::new();
                    while let Some(c) = it.peek().copied().filter(char::is_ascii_digit) {
                        s.push(c);
                        it.next();
                    }
                    s
                };
                let (na, nb) = (take(&mut ai), take(&mut bi));
                let (ta, tb) = (na.trim_start_matches('0'), nb.trim_start_matches('0'));
                let o = ta.len().cmp(&tb.len()).then_with(|| ta.cmp(tb)).then_with(|| na.len().cmp(&nb.len()));
                if o.is_ne() {
                    return o;
                }
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(&y);
                }
                ai.next();
                bi.next();
            }
        }
    }
}

/// The image files of a folder in natural order (empty if it has none).
pub fn list_images(dir: &Path) -> Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir).map_err(|e| IoError::Io { path: dir.into(), source: e })?;
    let mut files: Vec<PathBuf> =
        rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|f| f.is_file() && crate::is_image_path(f)).collect();
    files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    Ok(files)
}

/// The last bytes ffmpeg wrote to stderr (its error messages), drained by a thread so that a
/// chatty ffmpeg can never block on a full pipe.
pub(crate) type StderrTail = Arc<Mutex<Vec<u8>>>;

/// Starts the thread that keeps the last 8 KiB of `err`; it ends when the process closes it.
pub(crate) fn drain_stderr(mut err: impl Read + Send + 'static) -> (StderrTail, std::thread::JoinHandle<()>) {
    let tail: StderrTail = Arc::default();
    let sink = Arc::clone(&tail);
    let handle = std::thread::spawn(move || {
        let mut chunk = [0u8; 4096];
        while let Ok(n) = err.read(&mut chunk) {
            if n == 0 {
                break;
            }
            if let Ok(mut t) = sink.lock() {
                t.extend_from_slice(&chunk[..n]);
                let excess = t.len().saturating_sub(8192);
                t.drain(..excess);
            }
        }
    });
    (tail, handle)
}

/// A running ffmpeg decoder.
#[derive(Debug)]
struct Ffmpeg {
    child: Child,
    stdout: BufReader<ChildStdout>,
    stderr: StderrTail,
    /// The thread draining stderr; it ends when ffmpeg closes stderr (at exit).
    drain: Option<std::thread::JoinHandle<()>>,
    width: usize,
    height: usize,
    buf: Vec<u8>,
}

impl Drop for Ffmpeg {
    fn drop(&mut self) {
        // Stopped early (error or enough frames): do not leave the process behind.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[derive(Debug)]
enum Kind {
    Folder(Vec<PathBuf>),
    Y4m(Box<Y4mReader<BufReader<std::fs::File>>>),
    Ffmpeg(Box<Ffmpeg>),
}

/// A stream of RGB frames; iterate it, or call [`Frames::next_frame`].
#[derive(Debug)]
pub struct Frames {
    path: PathBuf,
    kind: Kind,
    len: Option<usize>,
    size: Option<(usize, usize)>,
    index: usize,
    done: bool,
    max_pixels: u64,
}

fn ffmpeg_missing(program: &str, e: std::io::Error) -> IoError {
    IoError::Ffmpeg(format!(
        "cannot run {program} ({e}); install ffmpeg (scripts/setup.sh does) or give a folder of images or a .y4m file"
    ))
}

/// `(width, height, frame count if the container knows it)` from ffprobe.
fn probe(path: &Path) -> Result<(usize, usize, Option<usize>)> {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-show_entries", "stream=width,height,nb_frames", "-of"])
        .arg("default=noprint_wrappers=1")
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| ffmpeg_missing("ffprobe", e))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let field = |k: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(k).and_then(|v| v.strip_prefix('=')))
            .and_then(|v| v.trim().parse().ok())
    };
    match (out.status.success(), field("width"), field("height")) {
        (true, Some(w), Some(h)) if w > 0 && h > 0 => Ok((w, h, field("nb_frames").filter(|&n| n > 0))),
        _ => Err(IoError::Video {
            path: path.into(),
            frame: 0,
            reason: format!("ffprobe finds no video stream: {}", String::from_utf8_lossy(&out.stderr).trim()),
        }),
    }
}

impl Ffmpeg {
    fn start(path: &Path, width: usize, height: usize) -> Result<Self> {
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", "-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| ffmpeg_missing("ffmpeg", e))?;
        let (Some(stdout), Some(err)) = (child.stdout.take(), child.stderr.take()) else {
            return Err(IoError::Ffmpeg("ffmpeg started without pipes".into()));
        };
        let (stderr, drain) = drain_stderr(err);
        let buf = vec![0u8; width * height * 3];
        Ok(Self {
            child,
            stdout: BufReader::with_capacity(1 << 20, stdout),
            stderr,
            drain: Some(drain),
            width,
            height,
            buf,
        })
    }

    fn stderr_text(&self) -> String {
        self.stderr.lock().map(|t| String::from_utf8_lossy(&t).trim().to_string()).unwrap_or_default()
    }

    /// The next frame; at the end, ffmpeg's exit status and messages decide between the end of
    /// the video and an error.
    fn next(&mut self, path: &Path, frame: usize) -> Result<Option<RgbImage>> {
        let n = self.buf.len();
        let mut got = 0;
        while got < n {
            match self.stdout.read(&mut self.buf[got..]) {
                Ok(0) => break,
                Ok(k) => got += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(IoError::Video { path: path.into(), frame, reason: e.to_string() }),
            }
        }
        if got == n {
            // One pass over the bytes (a copy the compiler vectorizes), not a call per pixel.
            let data: Vec<[u8; 3]> = self.buf.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let px = ocellus_image::Plane::from_vec(self.width, self.height, data).map_err(|e| IoError::Video {
                path: path.into(),
                frame,
                reason: e.to_string(),
            })?;
            return Ok(Some(RgbImage::U8(px)));
        }
        let status = self.child.wait().map_err(|e| IoError::Ffmpeg(e.to_string()))?;
        // ffmpeg has exited: its stderr is closed, so the drain has every message once joined.
        if let Some(d) = self.drain.take() {
            let _ = d.join();
        }
        let msg = self.stderr_text();
        if got > 0 || !status.success() || !msg.is_empty() {
            let why = if msg.is_empty() { format!("ffmpeg exited with {status}") } else { msg };
            let cut = if got > 0 { format!("truncated ({got} of {n} bytes); ") } else { String::new() };
            return Err(IoError::Video { path: path.into(), frame, reason: format!("{cut}{why}") });
        }
        Ok(None)
    }
}

impl Frames {
    /// Opens a folder of images (natural order), a `.y4m` file, or any other file through
    /// ffmpeg, with frames of up to [`DEFAULT_MAX_PIXELS`].
    pub fn open(path: impl AsRef<Path>) -> Result<Frames> {
        Self::open_within(path, DEFAULT_MAX_PIXELS)
    }

    /// [`Frames::open`] for frames of at most `max_pixels` pixels: a larger video is refused
    /// from its header, a larger image of a folder when it is reached.
    pub fn open_within(path: impl AsRef<Path>, max_pixels: u64) -> Result<Frames> {
        let path = path.as_ref();
        if !path.exists() {
            return Err(IoError::NotFound { path: path.into() });
        }
        let (kind, len, size) = if path.is_dir() {
            let files = list_images(path)?;
            if files.is_empty() {
                return Err(IoError::Invalid {
                    path: path.into(),
                    reason: "folder has no PNG, JPEG or PNM image".into(),
                });
            }
            let n = files.len();
            (Kind::Folder(files), Some(n), None)
        } else if path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("y4m")) {
            let f = std::fs::File::open(path).map_err(|e| IoError::Io { path: path.into(), source: e })?;
            let r = Y4mReader::new(BufReader::with_capacity(1 << 20, f), path)?;
            let size = (r.header().width, r.header().height);
            let frame_total = r.header().frame_bytes() + 6;
            // Frames carry no index: estimate the count from the file size when FRAME lines are bare.
            let len = std::fs::metadata(path).ok().map(|m| m.len() as usize / frame_total.max(1));
            (Kind::Y4m(Box::new(r)), len, Some(size))
        } else {
            let (w, h, n) = probe(path)?;
            (Kind::Ffmpeg(Box::new(Ffmpeg::start(path, w, h)?)), n, Some((w, h)))
        };
        if let Some((w, h)) = size {
            if w as u64 * h as u64 > max_pixels {
                return Err(IoError::TooLarge { path: path.into(), width: w as u64, height: h as u64, max_pixels });
            }
        }
        Ok(Frames { path: path.into(), kind, len, size, index: 0, done: false, max_pixels })
    }

    /// Number of frames when known in advance (folders, Y4M, and containers that store it).
    pub fn len_hint(&self) -> Option<usize> {
        self.len
    }

    /// Frame size, when known before the first frame (video files).
    pub fn size_hint(&self) -> Option<(usize, usize)> {
        self.size
    }

    /// Frames delivered so far.
    pub fn frames_read(&self) -> usize {
        self.index
    }

    /// The next frame, `None` at the end; an error names the frame where it happened.
    pub fn next_frame(&mut self) -> Result<Option<RgbImage>> {
        if self.done {
            return Ok(None);
        }
        let k = self.index;
        let r = match &mut self.kind {
            Kind::Folder(files) => match files.get(k) {
                Some(f) => read_image_within(f, self.max_pixels).map(Some).map_err(|e| IoError::Video {
                    path: self.path.clone(),
                    frame: k,
                    reason: e.to_string(),
                }),
                None => Ok(None),
            },
            Kind::Y4m(r) => r.next_frame(),
            Kind::Ffmpeg(f) => f.next(&self.path, k),
        };
        // A source that ends before its first frame (a Y4M of only a header, an empty video) is
        // an error, not an empty success.
        let r = match r {
            Ok(None) if k == 0 => {
                Err(IoError::Invalid { path: self.path.clone(), reason: "contains no frames".into() })
            }
            r => r,
        };
        let r = r.and_then(|f| match (f, self.size) {
            (Some(img), Some(s)) if img.size() != s => Err(IoError::Video {
                path: self.path.clone(),
                frame: k,
                reason: format!("frame is {}x{}, earlier frames are {}x{}", img.size().0, img.size().1, s.0, s.1),
            }),
            (f, _) => Ok(f),
        });
        match &r {
            Ok(Some(img)) => {
                self.size = Some(img.size());
                self.index += 1;
            }
            _ => self.done = true,
        }
        r
    }
}

impl Iterator for Frames {
    type Item = Result<RgbImage>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_frame().transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order() {
        let mut v = vec!["f10.png", "f2.png", "f1.png", "f02.png", "g.png"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, vec!["f1.png", "f2.png", "f02.png", "f10.png", "g.png"]);
    }
}
