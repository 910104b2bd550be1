//! Reading real files, writing maps, and clear errors for bad files.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use ocellus_io::{npy, pfm, read_image, IoError};
use ocellus_testdata::data_file;
use proptest::prelude::*;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ocellus-io-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn reads_real_png_jpeg_and_grey() {
    let a = read_image(data_file("astronaut.png")).unwrap();
    assert_eq!(a.size(), (512, 512));
    let r = read_image(data_file("rocket.jpg")).unwrap();
    assert_eq!(r.size(), (640, 427));
    let g = read_image(data_file("camera.png")).unwrap();
    // grey becomes R = G = B
    let p = g.get_f32(100, 100);
    assert!(p[0] == p[1] && p[1] == p[2]);
}

#[test]
fn sixteen_bit_rgba_and_pnm_inputs() {
    let img16 = image::ImageBuffer::<image::Rgba<u16>, _>::from_fn(9, 7, |x, y| {
        image::Rgba([(x * 7000) as u16, (y * 9000) as u16, 65535, 100])
    });
    let p = tmp("rgba16.png");
    img16.save(&p).unwrap();
    match read_image(&p).unwrap() {
        RgbImage::F32(pl) => {
            assert_eq!(pl.size(), (9, 7));
            assert!((pl.get(1, 0)[0] - 7000.0 / 65535.0).abs() < 1e-6, "16-bit precision kept");
            assert_eq!(pl.get(0, 0)[2], 1.0);
        }
        RgbImage::U8(_) => panic!("16-bit input must keep its precision"),
    }
    let grey = image::GrayImage::from_fn(5, 4, |x, _| image::Luma([(x * 50) as u8]));
    let p = tmp("g.pgm");
    grey.save(&p).unwrap();
    assert_eq!(read_image(&p).unwrap().get_f32(2, 1), [100.0 / 255.0; 3]);
}

#[test]
fn clear_errors_for_bad_files() {
    assert!(matches!(read_image("/definitely/not/here.png"), Err(IoError::NotFound { .. })));
    let empty = tmp("empty.png");
    std::fs::write(&empty, b"").unwrap();
    assert!(matches!(read_image(&empty), Err(IoError::EmptyFile { .. })));
    let text = tmp("notes.png");
    std::fs::write(&text, b"this is not an image at all").unwrap();
    assert!(matches!(read_image(&text), Err(IoError::Unsupported { .. })));
    let bytes = std::fs::read(data_file("chelsea.png")).unwrap();
    let trunc = tmp("trunc.png");
    std::fs::write(&trunc, &bytes[..bytes.len() / 3]).unwrap();
    let e = read_image(&trunc).unwrap_err();
    assert!(matches!(e, IoError::Corrupt { .. }), "{e}");
    assert!(e.to_string().contains("trunc.png"), "message names the file: {e}");
}

#[test]
fn npy_reads_fortran_order_and_round_trips() {
    // The reference maps are Fortran-ordered float64.
    let a = npy::read(data_file("reference/astronaut_stb_salmap_30x40.npy")).unwrap();
    assert_eq!(a.shape, vec![30, 40]);
    let mx = a.data.iter().cloned().fold(f64::MIN, f64::max);
    assert!(mx > 2.0 && mx < 2.4, "README says range about [0, 2.3]: {mx}");
    // Hand-made Fortran-order file: element (r, c) = 10 r + c.
    let mut header = String::from("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&(header.len() as u16).to_le_bytes());
    b.extend_from_slice(header.as_bytes());
    for c in 0..3 {
        for r in 0..2 {
            b.extend_from_slice(&((10 * r + c) as f64).to_le_bytes());
        }
    }
    let arr = npy::parse(&b, std::path::Path::new("x.npy")).unwrap();
    assert_eq!(arr.data, vec![0.0, 1.0, 2.0, 10.0, 11.0, 12.0]);
    let p = Plane::from_fn(4, 3, |x, y| x as f32 - y as f32 * 0.5);
    let f = tmp("m.npy");
    npy::write_plane(&f, &p).unwrap();
    let back = npy::read(&f).unwrap();
    assert_eq!(back.shape, vec![3, 4]);
    assert_eq!(back.data, p.to_vec().iter().map(|&v| v as f64).collect::<Vec<_>>());
    // f64 arrays of any rank come back bit for bit.
    let v: Vec<f64> = (0..24).map(|i| (i as f64).sqrt() * 1e-7 - 3.0).collect();
    let f = tmp("v.npy");
    npy::write_f64(&f, &[2, 3, 4], &v).unwrap();
    let back = npy::read(&f).unwrap();
    assert_eq!((back.shape, back.data), (vec![2, 3, 4], v));
}

#[test]
fn pfm_round_trip_and_middlebury_file() {
    let p = Plane::from_fn(5, 3, |x, y| (x * 10 + y) as f32 + 0.25);
    let f = tmp("m.pfm");
    pfm::write(&f, &p).unwrap();
    assert_eq!(pfm::read(&f).unwrap(), p);
    let d = pfm::read(data_file("motorcycle_disp.pfm")).unwrap();
    assert_eq!(d.size(), (741, 500));
    let finite: Vec<f32> = d.to_vec().into_iter().filter(|v| v.is_finite()).collect();
    assert!(finite.len() > 741 * 500 / 2);
    assert!(finite.iter().all(|&v| (0.0..300.0).contains(&v)));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn parsers_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300), magic in 0usize..3) {
        let mut b = bytes;
        match magic {
            1 => { let mut m = b"\x93NUMPY\x01\x00".to_vec(); m.extend(b); b = m; }
            2 => { let mut m = b"Pf\n3 2\n-1.0\n".to_vec(); m.extend(b); b = m; }
            _ => {}
        }
        let p = std::path::Path::new("fuzz");
        let _ = npy::parse(&b, p);
        let _ = pfm::parse(&b, p);
        let _ = ocellus_io::decode_image(&b, p);
    }
}
