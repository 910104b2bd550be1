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
