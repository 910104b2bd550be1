//! Writing a video of RGB frames by piping them into the ffmpeg program (MPEG-4 in `.mp4`).
//!
//! Everything that can be checked is checked before ffmpeg starts (even frame sizes, a frame
//! rate ffmpeg accepts, an output path that is not a folder and whose folder exists). When
//! ffmpeg dies anyway, the error says so with the tail of its messages; frames the caller
//! already wrote elsewhere are untouched.

use crate::video::{drain_stderr, StderrTail};
use crate::{IoError, Result};
use ocellus_image::Plane;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

/// Frame rates ffmpeg's MPEG-4 encoder accepts here (frames per second).
pub const FPS_RANGE: std::ops::RangeInclusive<u32> = 1..=1000;

/// An ffmpeg encoder fed one frame at a time.
#[derive(Debug)]
pub struct VideoWriter {
    path: PathBuf,
    child: Child,
    stdin: Option<ChildStdin>,
    stderr: StderrTail,
    drain: Option<std::thread::JoinHandle<()>>,
    size: (usize, usize),
    buf: Vec<u8>,
}

fn invalid(path: &Path, reason: String) -> IoError {
    IoError::Invalid { path: path.into(), reason }
}

/// Checks that a video can be written at `path` (not a folder; its folder exists), so that a
/// command can refuse before it starts work rather than when the first frame is ready.
pub fn check_output(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(invalid(path, "is a folder; the video needs a file name".into()));
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        if !parent.is_dir() {
            return Err(invalid(path, format!("folder {} does not exist", parent.display())));
        }
    }
    Ok(())
}

impl VideoWriter {
    /// Starts ffmpeg writing `path` (overwritten) at `fps` frames per second; `Ok(None)` when
    /// ffmpeg is not installed. Width and height must be even (the encoder's 4:2:0 chroma).
    pub fn start(path: &Path, width: usize, height: usize, fps: u32) -> Result<Option<Self>> {
        if width == 0 || height == 0 || width % 2 == 1 || height % 2 == 1 {
            return Err(invalid(path, format!("video frames must have even, non-zero sizes, got {width}x{height}")));
        }
        if !FPS_RANGE.contains(&fps) {
            return Err(invalid(
                path,
                format!("frame rate {fps} fps is outside {}..={}", FPS_RANGE.start(), FPS_RANGE.end()),
            ));
        }
        check_output(path)?;
        let spawned = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s"])
            .arg(format!("{width}x{height}"))
            .args(["-r", &fps.to_string(), "-i", "-", "-c:v", "mpeg4", "-q:v", "3", "-pix_fmt", "yuv420p"])
            .arg(path)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = match spawned {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(IoError::Ffmpeg(format!("cannot start ffmpeg: {e}"))),
        };
        let stdin = child.stdin.take();
        let (stderr, drain) = match child.stderr.take() {
            Some(err) => {
                let (tail, handle) = drain_stderr(err);
                (tail, Some(handle))
            }
            None => (StderrTail::default(), None),
        };
        Ok(Some(Self {
            path: path.into(),
            child,
            stdin,
            stderr,
            drain,
            size: (width, height),
            buf: Vec::with_capacity(width * height * 3),
        }))
    }

    /// The video's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends a frame of the video's size. When ffmpeg has stopped, the error carries its
    /// exit status and last messages.
    pub fn write(&mut self, frame: &Plane<[u8; 3]>) -> Result<()> {
        if frame.size() != self.size {
            return Err(invalid(
                &self.path,
                format!("video frame is {:?}, the video is {:?}", frame.size(), self.size),
            ));
        }
        self.buf.clear();
        for y in 0..frame.height() {
            self.buf.extend(frame.row(y).iter().flatten());
        }
        let Some(stdin) = self.stdin.as_mut() else {
            return Err(self.failure("ffmpeg input already closed"));
        };
        match stdin.write_all(&self.buf) {
            Ok(()) => Ok(()),
            Err(e) => {
                drop(self.stdin.take());
                Err(self.failure(&format!("ffmpeg stopped accepting frames ({e})")))
            }
        }
    }

    /// Closes the input and waits for ffmpeg to finish the file.
    pub fn finish(mut self) -> Result<()> {
        drop(self.stdin.take());
        match self.child.wait() {
            Ok(s) if s.success() => Ok(()),
            Ok(_) | Err(_) => Err(self.failure("ffmpeg failed finishing the video")),
        }
    }

    /// Waits for ffmpeg and builds the error: what happened, its exit status, its last messages.
    fn failure(&mut self, what: &str) -> IoError {
        let status = match self.child.wait() {
            Ok(s) => s.to_string(),
            Err(e) => format!("status unknown: {e}"),
        };
        if let Some(d) = self.drain.take() {
            let _ = d.join();
        }
        let tail = self.stderr.lock().map(|t| String::from_utf8_lossy(&t).trim().to_string()).unwrap_or_default();
        let tail: Vec<&str> = tail.lines().rev().take(6).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        let msg = if tail.is_empty() { "no message".to_string() } else { tail.join(" | ") };
        IoError::Ffmpeg(format!("{}: {what} ({status}); ffmpeg said: {msg}", self.path.display()))
    }
}

impl Drop for VideoWriter {
    fn drop(&mut self) {
        // Dropped before `finish` (an error elsewhere): close the input so ffmpeg ends, and reap it.
        drop(self.stdin.take());
        let _ = self.child.wait();
    }
}
