//! Files a careless or hostile user may give: each is refused with a clear error, before any
//! large allocation, never decoded into a silently wrong image.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use ocellus_io::{decode_image, decode_image_within, video::Frames, IoError};
use std::path::Path;

#[test]
fn a_truncated_jpeg_is_refused() {
    let bytes = std::fs::read(ocellus_testdata::data_file("rocket.jpg")).unwrap();
    assert!(decode_image(&bytes, Path::new("rocket.jpg")).is_ok());
    for keep in [bytes.len() - 2, bytes.len() / 2, bytes.len() - 1000] {
        let e = decode_image(&bytes[..keep], Path::new("cut.jpg")).unwrap_err();
        assert!(e.to_string().contains("truncated JPEG"), "{keep}: {e}");
    }
    // Padding after the end marker is allowed.
    let mut padded = bytes.clone();
    padded.extend([0u8; 16]);
    assert!(decode_image(&padded, Path::new("padded.jpg")).is_ok());
}

#[test]
fn an_image_over_the_pixel_limit_is_refused_from_its_header() {
    // A PGM header claiming 20000x20000 pixels with almost no data: refused by size, not
    // by running out of memory or data.
    let mut pgm = b"P5\n20000 20000\n255\n".to_vec();
    pgm.extend([0u8; 64]);
    match decode_image(&pgm, Path::new("huge.pgm")) {
        Err(IoError::TooLarge { width: 20000, height: 20000, max_pixels, .. }) => {
            assert_eq!(max_pixels, ocellus_io::DEFAULT_MAX_PIXELS)
        }
        other => panic!("{other:?}"),
    }
    let small = b"P5\n4 2\n255\n\x00\x01\x02\x03\x04\x05\x06\x07";
    assert!(decode_image_within(small, Path::new("s.pgm"), 8).is_ok());
    let e = decode_image_within(small, Path::new("s.pgm"), 7).unwrap_err();
    assert!(e.to_string().contains("over the limit"), "{e}");
}

#[test]
fn a_y4m_without_frames_is_an_error() {
    let dir = std::env::temp_dir().join(format!("ocellus-badfiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("header.y4m");
    std::fs::write(&p, b"YUV4MPEG2 W64 H48 F30:1 Ip A1:1 C444\n").unwrap();
    let mut f = Frames::open(&p).unwrap();
    let e = f.next_frame().unwrap_err();
    assert!(e.to_string().contains("no frames"), "{e}");
    // A Y4M header too large for the limit is refused on opening.
    let q = dir.join("big.y4m");
    std::fs::write(&q, b"YUV4MPEG2 W8000 H8000 F30:1 Ip A1:1 C444\n").unwrap();
    assert!(matches!(Frames::open_within(&q, 1_000_000), Err(IoError::TooLarge { .. })));
    std::fs::remove_dir_all(&dir).unwrap();
}

proptest::proptest! {
    /// Whatever the text, the CSV reader returns rows of exactly the asked number of finite
    /// numbers, or an error; rows written from numbers read back equal.
    #[test]
    fn csv_rows_have_exactly_the_asked_columns(text in "[0-9a-z,;. \\t\\n#eE+-]{0,200}", columns in 1usize..6) {
        if let Ok(rows) = ocellus_io::csv::parse_rows(text.as_bytes(), Path::new("p.csv"), columns, "numbers") {
            proptest::prop_assert!(rows.iter().all(|r| r.len() == columns && r.iter().all(|v| v.is_finite())));
        }
    }

    #[test]
    fn csv_round_trip(rows in proptest::collection::vec(proptest::collection::vec(-1e9f64..1e9, 3), 0..20)) {
        let text: String = rows.iter().map(|r| format!("{},{},{}\n", r[0], r[1], r[2])).collect();
        let back = ocellus_io::csv::parse_rows(text.as_bytes(), Path::new("p.csv"), 3, "numbers").unwrap();
        proptest::prop_assert_eq!(back, rows);
    }
}

/// Headers whose sizes overflow when multiplied (found by the fuzzers): errors, not panics
/// or wrapped sizes.
#[test]
fn overflowing_sizes_in_headers_are_errors() {
    let pfm = b"Pf\n77777777777777777777 2\n-1.0\n\0\0\0\0";
    assert!(ocellus_io::pfm::parse(pfm, Path::new("o.pfm")).is_err());
    let pfm = b"Pf\n4611686018427387904 2\n-1.0\n\0\0\0\0";
    assert!(ocellus_io::pfm::parse(pfm, Path::new("o.pfm")).is_err());
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (4294967296, 4294967296, 16), }";
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    npy.extend((header.len() as u16).to_le_bytes());
    npy.extend(header.as_bytes());
    npy.extend([0u8; 16]);
    let e = ocellus_io::npy::parse(&npy, Path::new("o.npy")).unwrap_err();
    assert!(e.to_string().contains("overflow"), "{e}");
}
