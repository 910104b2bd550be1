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
