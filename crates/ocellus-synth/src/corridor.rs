//! A corridor world on real imagery for view planning (SPEC 2.6, the seed's experiment).
//!
//! Plan (metres): the corridor runs along +x from `x = -1` to `x = length_m`, between a right
//! wall at `y = 0` and a left wall at `y = width_m`; walls are `wall_height_m` high and
//! textured with a real brick photograph, the floor with gravel, the ceiling plain. Landmarks
//! are posters (distinct real image patches) on the walls, centred at camera height. A person
//! (a real image patch) can stand in the corridor as a vertical panel facing the robot.
//!
//! The camera is a pinhole at height `camera_height_m`, at the robot's position, looking
//! horizontally at world angle `heading + pan` (degrees, counter-clockwise from +x). Each
//! image column is a ray cast against the walls and the person's panel; each row takes the
//! wall, floor or ceiling at that height. Textures are sampled bilinearly; optional Gaussian
//! sensor noise is seeded per frame.

use crate::texture::sample;
use crate::{Result, SynthError};
use ocellus_image::convert::RgbImage;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};

/// Which wall a poster hangs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Wall {
    /// `y = width_m`.
    Left,
    /// `y = 0`.
    Right,
}

/// A poster landmark: centre `x_m` along the wall, at camera height.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Poster {
    /// Position along the corridor, metres.
    pub x_m: f64,
    /// Which wall.
    pub wall: Wall,
    /// Width and height, metres.
    pub size_m: f64,
}

/// A person: a vertical panel across the corridor at `x_m`, centred at `y_m`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Person {
    /// Distance along the corridor, metres.
    pub x_m: f64,
    /// Lateral centre, metres.
    pub y_m: f64,
    /// Width, metres.
    pub width_m: f64,
    /// Height, metres.
    pub height_m: f64,
}

/// Geometry and camera of the corridor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorridorConfig {
    /// Length, metres.
    pub length_m: f64,
    /// Width, metres.
    pub width_m: f64,
    /// Wall height, metres.
    pub wall_height_m: f64,
    /// Camera height, metres.
    pub camera_height_m: f64,
    /// Image size, pixels.
    pub image_size: (usize, usize),
    /// Horizontal field of view, degrees.
    pub hfov_deg: f64,
    /// Sensor noise, grey levels (0: none).
    pub noise_sigma: f32,
    /// Texture resolution, pixels per metre.
    pub texture_px_per_m: f64,
    /// The landmarks.
    pub posters: Vec<Poster>,
    /// The person (shown only when asked at render time).
    pub person: Person,
}

impl Default for CorridorConfig {
    /// A 14 m x 2.5 m corridor, walls 2.5 m, camera at 1.0 m, 640x480 with a 100 degree field
    /// of view, four 0.6 m posters (left wall at 3 and 9 m, right wall at 5.5 and 11 m), and a
    /// person 1.8 m tall at (4.5, 1.6) m.
    fn default() -> Self {
        Self {
            length_m: 14.0,
            width_m: 2.5,
            wall_height_m: 2.5,
            camera_height_m: 1.0,
            image_size: (640, 480),
            hfov_deg: 100.0,
            noise_sigma: 1.0,
            texture_px_per_m: 256.0,
            posters: vec![
                Poster { x_m: 3.0, wall: Wall::Left, size_m: 0.6 },
                Poster { x_m: 5.5, wall: Wall::Right, size_m: 0.6 },
                Poster { x_m: 9.0, wall: Wall::Left, size_m: 0.6 },
                Poster { x_m: 11.0, wall: Wall::Right, size_m: 0.6 },
            ],
            person: Person { x_m: 4.5, y_m: 1.6, width_m: 0.6, height_m: 1.8 },
        }
    }
}

/// Images the corridor is made of: grey wall and floor textures, one picture per poster, the
/// person.
pub struct CorridorTextures {
    /// Wall texture (grey).
    pub wall: RgbImage,
    /// Floor texture (grey).
    pub floor: RgbImage,
    /// Poster pictures, one per poster.
    pub posters: Vec<RgbImage>,
    /// The person's picture.
    pub person: RgbImage,
}

/// The renderer.
#[derive(Debug)]
pub struct Corridor {
    cfg: CorridorConfig,
    wall: Plane<[f32; 3]>,
    floor: Plane<[f32; 3]>,
    posters: Vec<Plane<[f32; 3]>>,
    person: Plane<[f32; 3]>,
    focal_px: f64,
}

fn to_f32(img: &RgbImage) -> Plane<[f32; 3]> {
    let (w, h) = img.size();
    Plane::from_fn(w, h, |x, y| img.get_f32(x, y))
}

impl Corridor {
    /// A corridor with these textures.
    pub fn new(cfg: CorridorConfig, tex: &CorridorTextures) -> Result<Self> {
        let bad = |m: String| Err(SynthError::InvalidConfig(m));
        let (w, h) = cfg.image_size;
        if w < 16 || h < 16 || w > 8192 || h > 8192 {
            return bad(format!("image {w}x{h}"));
        }
        let dims = [cfg.length_m, cfg.width_m, cfg.wall_height_m, cfg.camera_height_m, cfg.texture_px_per_m];
        if !dims.iter().all(|v| v.is_finite() && *v > 0.0) || cfg.camera_height_m >= cfg.wall_height_m {
            return bad("corridor sizes must be > 0, camera below the wall top".into());
        }
        if !(cfg.hfov_deg > 1.0 && cfg.hfov_deg < 170.0) {
            return bad(format!("field of view {} degrees", cfg.hfov_deg));
        }
        if tex.posters.len() != cfg.posters.len() {
            return bad(format!("{} posters, {} poster pictures", cfg.posters.len(), tex.posters.len()));
        }
        let all = [&tex.wall, &tex.floor, &tex.person].into_iter().chain(tex.posters.iter());
        if all.into_iter().any(|i| i.size().0 == 0 || i.size().1 == 0) {
            return bad("empty texture".into());
        }
        let focal_px = (w as f64 / 2.0) / (cfg.hfov_deg.to_radians() / 2.0).tan();
        Ok(Self {
            wall: to_f32(&tex.wall),
            floor: to_f32(&tex.floor),
            posters: tex.posters.iter().map(to_f32).collect(),
            person: to_f32(&tex.person),
            focal_px,
            cfg,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &CorridorConfig {
        &self.cfg
    }

    /// Focal length in pixels.
    pub fn focal_px(&self) -> f64 {
        self.focal_px
    }

    /// Landmark positions (poster centres on the walls), metres.
    pub fn landmarks(&self) -> Vec<(f64, f64)> {
        self.cfg.posters.iter().map(|p| (p.x_m, if p.wall == Wall::Left { self.cfg.width_m } else { 0.0 })).collect()
    }

    /// Image column where world direction `angle_deg` appears for a camera looking at
    /// `axis_deg`, or None when outside the field of view.
    pub fn column_of(&self, angle_deg: f64, axis_deg: f64) -> Option<f64> {
        let off = (angle_deg - axis_deg + 180.0).rem_euclid(360.0) - 180.0;
        if off.abs() >= 90.0 {
            return None;
        }
        let u = (self.cfg.image_size.0 as f64 - 1.0) / 2.0 - self.focal_px * off.to_radians().tan();
        (u >= -0.5 && u <= self.cfg.image_size.0 as f64 - 0.5).then_some(u)
    }

    /// Renders the view from (`x_m`, `y_m`) with the camera at world angle
    /// `heading_deg + pan_deg`; the person is drawn when `show_person`; `noise_seed` seeds the
    /// sensor noise.
    pub fn render(&self, x_m: f64, y_m: f64, axis_deg: f64, show_person: bool, noise_seed: u64) -> RgbImage {
        let c = &self.cfg;
        let (w, h) = c.image_size;
        let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
        let axis = axis_deg.to_radians();
        let mut img = Plane::new(w, h);
        let mut rng = SplitMix64::new(noise_seed);
        for u in 0..w {
            let off = ((cx - u as f64) / self.focal_px).atan();
            let phi = axis + off;
            let (dx, dy) = (phi.cos(), phi.sin());
            // Nearest wall along the ray.
            let mut t_wall = f64::INFINITY;
            let mut surface = (0.0, Wall::Left, false); // (s along the surface, side wall, end wall?)
            if dy > 1e-12 {
                let t = (c.width_m - y_m) / dy;
                if t < t_wall {
                    t_wall = t;
                    surface = (x_m + t * dx, Wall::Left, false);
                }
            } else if dy < -1e-12 {
                let t = -y_m / dy;
                if t < t_wall {
                    t_wall = t;
                    surface = (x_m + t * dx, Wall::Right, false);
                }
            }
            let end = if dx > 1e-12 {
                (c.length_m - x_m) / dx
            } else if dx < -1e-12 {
                (-1.0 - x_m) / dx
            } else {
                f64::INFINITY
            };
            if end < t_wall {
                t_wall = end;
                surface = (y_m + end * dy, Wall::Left, true);
            }
            // The person's panel (a plane x = const facing the robot).
            let p = &c.person;
            let person_hit = (show_person && dx > 1e-12)
                .then(|| (p.x_m - x_m) / dx)
                .filter(|&t| t > 0.0 && t < t_wall)
                .map(|t| (t, y_m + t * dy - (p.y_m - p.width_m / 2.0)))
                .filter(|&(_, s)| (0.0..p.width_m).contains(&s));
            let cos_off = off.cos();
            for v in 0..h {
                // Height of this pixel's ray at horizontal distance t (depth along the optical
                // axis t cos(off)): z = hc + (cy - v) t cos(off) / f.
                let slope = (cy - v as f64) / self.focal_px;
                let mut px = None;
                if let Some((t, s)) = person_hit {
                    let z = c.camera_height_m + slope * t * cos_off;
                    if (0.0..p.height_m).contains(&z) {
                        let tu = s / p.width_m * self.person.width() as f64 - 0.5;
                        let tv = (p.height_m - z) / p.height_m * self.person.height() as f64 - 0.5;
                        px = Some(sample(&self.person, self.person.width() as f64 - 1.0 - tu, tv, false, false));
                    }
                }
                let px = px.unwrap_or_else(|| {
                    let z = c.camera_height_m + slope * t_wall * cos_off;
                    if z < 0.0 {
                        // Floor: where the ray meets z = 0.
                        let t = c.camera_height_m / (-slope * cos_off);
                        let (fx, fy) = (x_m + t * dx, y_m + t * dy);
                        sample(&self.floor, fx * c.texture_px_per_m, fy * c.texture_px_per_m, true, true)
                    } else if z > c.wall_height_m {
                        [0.82, 0.82, 0.80]
                    } else {
                        self.wall_texel(surface, z)
                    }
                });
                img.set(u, v, px);
            }
        }
        let sigma = c.noise_sigma / 255.0;
        RgbImage::U8(Plane::from_fn(w, h, |x, y| {
            let mut p = img.get(x, y);
            if sigma > 0.0 {
                p.iter_mut().for_each(|v| *v += sigma * rng.normal() as f32);
            }
            p.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
        }))
    }

    /// Wall colour at position `s` along the surface and height `z`: a poster if one covers it.
    fn wall_texel(&self, (s, wall, end): (f64, Wall, bool), z: f64) -> [f32; 3] {
        let c = &self.cfg;
        if !end {
            for (i, p) in c.posters.iter().enumerate() {
                let half = p.size_m / 2.0;
                let (ds, dz) = (s - p.x_m, z - c.camera_height_m);
                if p.wall == wall && ds.abs() < half && dz.abs() < half {
                    let t = &self.posters[i];
                    // Seen from inside the corridor the left wall runs right to left.
                    let fu = if wall == Wall::Left { 0.5 - ds / p.size_m } else { 0.5 + ds / p.size_m };
                    let fv = 0.5 - dz / p.size_m;
                    return sample(t, fu * t.width() as f64 - 0.5, fv * t.height() as f64 - 0.5, false, false);
                }
            }
        }
        let k = c.texture_px_per_m;
        sample(&self.wall, s * k, (c.wall_height_m - z) * k, true, true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn textures() -> CorridorTextures {
        let solid = |c: [u8; 3]| RgbImage::U8(Plane::from_fn(8, 8, |_, _| c));
        CorridorTextures {
            wall: solid([100, 100, 100]),
            floor: solid([50, 50, 50]),
            posters: vec![solid([255, 0, 0]), solid([0, 255, 0]), solid([0, 0, 255]), solid([255, 255, 0])],
            person: solid([255, 0, 255]),
        }
    }

    fn corridor() -> Corridor {
        Corridor::new(CorridorConfig { noise_sigma: 0.0, ..Default::default() }, &textures()).unwrap()
    }

    #[test]
    fn posters_appear_where_the_pinhole_model_puts_them() {
        let c = corridor();
        let (x, y) = (0.0, 1.25);
        for (i, (lx, ly)) in c.landmarks().into_iter().enumerate() {
            let bearing = (ly - y).atan2(lx - x).to_degrees();
            let img = c.render(x, y, bearing, false, 0).to_u8();
            // Looking straight at the poster: its colour at the image centre.
            let want = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 0]][i];
            assert_eq!(img.get(320, 240), want, "poster {i}");
            // And a column predicted by column_of for a camera turned 20 degrees away.
            let u = c.column_of(bearing, bearing + 20.0).unwrap().round() as usize;
            let img = c.render(x, y, bearing + 20.0, false, 0).to_u8();
            assert_eq!(img.get(u, 240), want, "poster {i} at column {u}");
        }
    }

    #[test]
    fn floor_ceiling_walls_and_person() {
        let c = corridor();
        let img = c.render(0.0, 1.25, 0.0, false, 0).to_u8();
        assert_eq!(img.get(320, 479), [50, 50, 50], "floor below");
        assert_eq!(img.get(320, 0), [209, 209, 204], "ceiling above");
        assert_eq!(img.get(0, 240), [100, 100, 100], "left wall at the left edge");
        let p = c.config().person;
        let bearing = (p.y_m - 1.25f64).atan2(p.x_m).to_degrees();
        let with = c.render(0.0, 1.25, bearing, true, 0).to_u8();
        assert_eq!(with.get(320, 240), [255, 0, 255]);
        assert_ne!(c.render(0.0, 1.25, bearing, false, 0).to_u8().get(320, 240), [255, 0, 255]);
    }

    #[test]
    fn straight_lines_stay_straight() {
        // The top edge of the left wall is a straight line in a pinhole image: find it in
        // three columns (wall grey below, ceiling above) and check they are collinear.
        let c = corridor();
        let img = c.render(0.0, 1.25, 30.0, false, 0).to_u8();
        let edge = |u: usize| (0..240).find(|&v| img.get(u, v) != [209, 209, 204]).unwrap() as f64;
        let (a, b, m) = (edge(20), edge(220), edge(120));
        assert!((m - (a + b) / 2.0).abs() <= 1.0, "edge rows {a} {m} {b}");
    }

    #[test]
    fn noise_is_seeded() {
        let c = Corridor::new(CorridorConfig::default(), &textures()).unwrap();
        let a = c.render(1.0, 1.25, 30.0, false, 7).to_u8().to_vec();
        assert_eq!(a, c.render(1.0, 1.25, 30.0, false, 7).to_u8().to_vec());
        assert_ne!(a, c.render(1.0, 1.25, 30.0, false, 8).to_u8().to_vec());
    }
}
