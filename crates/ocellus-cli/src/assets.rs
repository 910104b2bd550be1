//! The built-in images (see `assets/LICENSES.md`), embedded so the binary needs no files.

/// (name, encoded bytes) of each built-in image.
pub const IMAGES: &[(&str, &[u8])] = &[
    ("astronaut.png", include_bytes!("../../../assets/astronaut.png")),
    ("chelsea.png", include_bytes!("../../../assets/chelsea.png")),
    ("coffee.png", include_bytes!("../../../assets/coffee.png")),
    ("rocket.jpg", include_bytes!("../../../assets/rocket.jpg")),
];

/// The textures (grey, CC0): brick and gravel for the corridor, grass.
pub const TEXTURES: &[(&str, &[u8])] = &[
    ("brick.png", include_bytes!("../../../assets/brick.png")),
    ("gravel.png", include_bytes!("../../../assets/gravel.png")),
    ("grass.png", include_bytes!("../../../assets/grass.png")),
];

/// The demo's data beyond the built-in images (see `testdata/LICENSES.md`): the Middlebury
/// 2014 motorcycle pair with its ground-truth disparity, and four MIT1003 stimuli with their
/// fixation maps; (path under the demo's `inputs/`, bytes).
pub const DEMO_DATA: &[(&str, &[u8])] = &[
    ("motorcycle_left.png", include_bytes!("../../../testdata/motorcycle_left.png")),
    ("motorcycle_right.png", include_bytes!("../../../testdata/motorcycle_right.png")),
    ("motorcycle_disp.pfm", include_bytes!("../../../testdata/motorcycle_disp.pfm")),
    (
        "mit1003/stimuli/i05june05_static_street_boston_p1010764.jpg",
        include_bytes!("../../../testdata/mit1003/stimuli/i05june05_static_street_boston_p1010764.jpg"),
    ),
    (
        "mit1003/stimuli/i05june05_static_street_boston_p1010785.jpg",
        include_bytes!("../../../testdata/mit1003/stimuli/i05june05_static_street_boston_p1010785.jpg"),
    ),
    (
        "mit1003/stimuli/i05june05_static_street_boston_p1010800.jpg",
        include_bytes!("../../../testdata/mit1003/stimuli/i05june05_static_street_boston_p1010800.jpg"),
    ),
    (
        "mit1003/stimuli/i05june05_static_street_boston_p1010806.jpg",
        include_bytes!("../../../testdata/mit1003/stimuli/i05june05_static_street_boston_p1010806.jpg"),
    ),
    (
        "mit1003/fixation_maps/i05june05_static_street_boston_p1010764.jpg",
        include_bytes!("../../../testdata/mit1003/fixation_maps/i05june05_static_street_boston_p1010764.jpg"),
    ),
    (
        "mit1003/fixation_maps/i05june05_static_street_boston_p1010785.jpg",
        include_bytes!("../../../testdata/mit1003/fixation_maps/i05june05_static_street_boston_p1010785.jpg"),
    ),
    (
        "mit1003/fixation_maps/i05june05_static_street_boston_p1010800.jpg",
        include_bytes!("../../../testdata/mit1003/fixation_maps/i05june05_static_street_boston_p1010800.jpg"),
    ),
    (
        "mit1003/fixation_maps/i05june05_static_street_boston_p1010806.jpg",
        include_bytes!("../../../testdata/mit1003/fixation_maps/i05june05_static_street_boston_p1010806.jpg"),
    ),
];

/// A built-in image or texture, decoded.
pub fn decode(name: &str) -> anyhow::Result<ocellus_image::convert::RgbImage> {
    let bytes = IMAGES
        .iter()
        .chain(TEXTURES)
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .ok_or_else(|| anyhow::anyhow!("no built-in image {name}"))?;
    Ok(ocellus_io::decode_image(bytes, std::path::Path::new(name))?)
}
