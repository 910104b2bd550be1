//! Frame sources on videos made from the project's own images: image folders, Y4M (ours and
//! ffmpeg's), and other containers through the ffmpeg program (installed by scripts/setup.sh).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_image::convert::RgbImage;
use ocellus_io::video::Frames;
use ocellus_io::y4m::Y4mWriter;
use ocellus_synth::attention_scenes::{Scenario, SceneConfig, SceneGenerator};
use ocellus_testdata::data_file;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ocellus-video-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Eight 160x120 frames of a pan over real photographs.
fn frames() -> Vec<RgbImage> {
    let world: Vec<_> =
        ["coffee.png", "rocket.jpg"].iter().map(|n| ocellus_io::read_image(data_file(n)).unwrap()).collect();
    let object = ocellus_io::read_image(data_file("chelsea.png")).unwrap();
    let cfg = SceneConfig { width: 160, height: 120, frames: 8, ..SceneConfig::new(Scenario::Pan) };
    let g = SceneGenerator::new(cfg, &world, &object).unwrap();
    (0..8).map(|k| g.frame(k).unwrap().0).collect()
}

fn write_pngs(frames: &[RgbImage], dir: &Path) {
    for (k, f) in frames.iter().enumerate() {
        ocellus_io::write_png(dir.join(format!("f{k}.png")), &f.to_u8()).unwrap();
    }
}

fn ffmpeg(args: &[&str]) {
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-y"])
        .args(args)
        .output()
        .expect("ffmpeg (scripts/setup.sh installs it)");
    assert!(o.status.success(), "ffmpeg {args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// Encodes the numbered PNGs of `pattern` with `codec` and `pix_fmt` into `out`.
fn encode_pngs(pattern: &Path, codec: &str, pix_fmt: &str, out: &Path) {
    let (p, o) = (pattern.to_str().unwrap(), out.to_str().unwrap());
    ffmpeg(&["-framerate", "30", "-i", p, "-c:v", codec, "-pix_fmt", pix_fmt, o]);
}

fn read_all(path: &Path) -> (Vec<RgbImage>, Option<usize>) {
    let mut f = Frames::open(path).unwrap();
    let hint = f.len_hint();
    (f.by_ref().map(|r| r.unwrap()).collect(), hint)
}

fn max_diff(a: &RgbImage, b: &RgbImage) -> i32 {
    let (a, b) = (a.to_u8().to_vec(), b.to_u8().to_vec());
    a.iter().zip(&b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] as i32 - q[c] as i32).abs())).max().unwrap()
}

#[test]
fn folder_y4m_and_ffmpeg_sources_deliver_the_same_frames() {
    let want = frames();
    let dir = tmpdir("src");
    let pngs = dir.join("pngs");
    std::fs::create_dir_all(&pngs).unwrap();
    write_pngs(&want, &pngs);
    // Folder, natural order (f2 before f10 would matter with more frames; here f0..f7).
    let (got, hint) = read_all(&pngs);
    assert_eq!(hint, Some(8));
    assert!(got.iter().zip(&want).all(|(g, w)| max_diff(g, w) == 0));
    // Our Y4M writer and reader: within one grey level (8-bit YCbCr round trip).
    let y4m = dir.join("ours.y4m");
    let mut w = Y4mWriter::new(std::fs::File::create(&y4m).unwrap(), 160, 120, (30, 1)).unwrap();
    want.iter().for_each(|f| w.write_frame(f).unwrap());
    w.finish().unwrap();
    let (got, hint) = read_all(&y4m);
    assert_eq!((got.len(), hint), (8, Some(8)));
    assert!(got.iter().zip(&want).all(|(g, w)| max_diff(g, w) <= 1));
    // Lossless RGB video through ffmpeg: exact.
    let pattern = pngs.join("f%d.png");
    let mkv = dir.join("lossless.mkv");
    encode_pngs(&pattern, "ffv1", "bgr0", &mkv);
    let (got, _) = read_all(&mkv);
    assert_eq!(got.len(), 8);
    assert!(got.iter().zip(&want).all(|(g, w)| max_diff(g, w) == 0));
    // ffmpeg's own Y4M (4:2:0, limited range) read by our reader: chroma subsampling costs
    // colour detail, so compare the mean error.
    let y4m_ff = dir.join("ffmpeg.y4m");
    ffmpeg(&["-framerate", "30", "-i", pattern.to_str().unwrap(), "-pix_fmt", "yuv420p", y4m_ff.to_str().unwrap()]);
    let (got, _) = read_all(&y4m_ff);
    assert_eq!(got.len(), 8);
    for (g, w) in got.iter().zip(&want) {
        let (a, b) = (g.to_u8().to_vec(), w.to_u8().to_vec());
        let mean =
            a.iter().zip(&b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).abs())).sum::<f64>()
                / (3 * a.len()) as f64;
        assert!(mean < 4.0, "mean error {mean} grey levels");
    }
}

#[test]
fn truncated_and_corrupt_videos_fail_at_the_right_frame() {
    let want = frames();
    let dir = tmpdir("bad");
    let y4m = dir.join("cut.y4m");
    let mut w = Y4mWriter::new(Vec::new(), 160, 120, (30, 1)).unwrap();
    want.iter().for_each(|f| w.write_frame(f).unwrap());
    let bytes = w.finish().unwrap();
    let frame_len = 6 + 3 * 160 * 120;
    let header_len = bytes.len() - 8 * frame_len;
    // Cut in the middle of frame 5: frames 0-4 arrive, then an error naming frame 5.
    std::fs::write(&y4m, &bytes[..header_len + 5 * frame_len + 1000]).unwrap();
    let mut f = Frames::open(&y4m).unwrap();
    for _ in 0..5 {
        assert!(f.next_frame().unwrap().is_some());
    }
    let e = f.next_frame().unwrap_err();
    assert_eq!(e.frame(), Some(5), "{e}");
    assert!(e.to_string().contains("truncated"), "{e}");
    assert!(f.next_frame().unwrap().is_none(), "stays ended");
    // A file that is no video at all: a clear error before any frame.
    let junk = dir.join("junk.mp4");
    std::fs::write(&junk, b"this is not a video").unwrap();
    let e = Frames::open(&junk).unwrap_err();
    assert!(e.to_string().contains("frame 0"), "{e}");
    // A raw-video stream through ffmpeg cut mid-frame: the frames before arrive, then the error.
    let pngs = dir.join("pngs");
    std::fs::create_dir_all(&pngs).unwrap();
    write_pngs(&want, &pngs);
    let nut = dir.join("raw.nut");
    let pattern = pngs.join("f%d.png");
    encode_pngs(&pattern, "rawvideo", "rgb24", &nut);
    let full = std::fs::read(&nut).unwrap();
    let cut = dir.join("cut.nut");
    std::fs::write(&cut, &full[..full.len() * 5 / 8 + 500]).unwrap();
    let mut f = Frames::open(&cut).unwrap();
    let mut n = 0;
    let err = loop {
        match f.next_frame() {
            Ok(Some(_)) => n += 1,
            Ok(None) => break None,
            Err(e) => break Some(e),
        }
    };
    println!("cut NUT file: {n} frames, then {err:?}");
    assert!((4..=6).contains(&n), "{n} frames before the cut");
    let e = err.expect("a cut video ends with an error");
    assert_eq!(e.frame(), Some(n));
}
