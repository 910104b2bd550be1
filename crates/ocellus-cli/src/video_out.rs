//! Writing a video of RGB frames by piping them into the ffmpeg program (MPEG-4 in .mp4).

use anyhow::{bail, Context, Result};
use ocellus_image::Plane;
use std::io::Write;
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};

/// An ffmpeg encoder fed one frame at a time.
pub struct VideoWriter {
    child: Child,
    stdin: Option<ChildStdin>,
    size: (usize, usize),
    buf: Vec<u8>,
}

impl VideoWriter {
    /// Starts ffmpeg writing `path` at `fps`; `None` when ffmpeg is not installed.
    pub fn start(path: &Path, width: usize, height: usize, fps: u32) -> Result<Option<Self>> {
        if width % 2 == 1 || height % 2 == 1 {
            bail!("video frames must have even sizes, got {width}x{height}");
        }
        let spawned = Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s"])
            .arg(format!("{width}x{height}"))
            .args(["-r", &fps.to_string(), "-i", "-", "-c:v", "mpeg4", "-q:v", "3", "-pix_fmt", "yuv420p"])
            .arg(path)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn();
        let mut child = match spawned {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e).context("cannot start ffmpeg"),
        };
        let stdin = child.stdin.take();
        Ok(Some(Self { child, stdin, size: (width, height), buf: Vec::with_capacity(width * height * 3) }))
    }

    /// Appends a frame of the video's size.
    pub fn write(&mut self, frame: &Plane<[u8; 3]>) -> Result<()> {
        if frame.size() != self.size {
            bail!("video frame is {:?}, the video is {:?}", frame.size(), self.size);
        }
        self.buf.clear();
        for y in 0..frame.height() {
            self.buf.extend(frame.row(y).iter().flatten());
        }
        let Some(stdin) = self.stdin.as_mut() else { bail!("ffmpeg input closed") };
        stdin.write_all(&self.buf).context("ffmpeg stopped accepting frames")
    }

    /// Closes the input and waits for ffmpeg to finish the file.
    pub fn finish(mut self) -> Result<()> {
        drop(self.stdin.take());
        let status = self.child.wait().context("ffmpeg")?;
        if !status.success() {
            bail!("ffmpeg failed ({status}) writing the video");
        }
        Ok(())
    }
}
