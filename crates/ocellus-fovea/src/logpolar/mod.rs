//! The retino-cortical (log-polar) map (SPEC 4.1).
//!
//! Geometry, about the gaze point c = (cx, cy) (pixel centres at integers):
//! - `fovea_rings` F linear rings cover the fovea, radii `rho_0 k / F`, k = 0..=F: small
//!   uniform fields, so the fovea is sampled at about one field per pixel instead of
//!   collapsing into the log singularity at the centre;
//! - `rings` R log rings cover rho_0..rho_max, radii `rho_0 a^i`, with the ring ratio
//!   `a = (rho_max / rho_0)^(1 / R)`: xi = log(rho) in steps of log(a);
//! - `sectors` S sectors split the angle eta = atan2(y - cy, x - cx) into steps of 2 pi / S
//!   starting at +x and turning towards +y (clockwise on the screen).
//!
//! The cortical image has one column per sector (eta) and one row per ring (fovea rows
//! first, then log rings outwards): a rotation of the input about the gaze point by k sectors
//! is a cyclic shift of the columns by k, and a scaling by a^k about the gaze point a shift of
//! the log rows by k.
//!
//! Receptive fields grow with eccentricity, and no cell is a point sample (point sampling,
//! what a remap does, aliases in the periphery, where one sample stands for hundreds of
//! pixels). Large fields read a box pyramid level instead of the full-resolution pixels: the
//! coarsest level whose texels still fit `min_field_texels` times across the field's smaller
//! side. Two field shapes ([`Fields`]):
//! - `Pyramid` (default): one bilinear read of that level at the cell's centroid: a smooth
//!   field about the cell's size (the level's box convolved with a tent), 4 table entries per
//!   cell. Per frame: the pyramid over the disc once, then the table (about 30 us for 640x480
//!   grey to 132 x 128 cells on one core with AVX2).
//! - `Area`: the exact mean of the bilinear image over the cell's annular sector, from a sparse
//!   weight table (6-13 entries per cell): the most faithful, about 5x slower.
//!
//! The per-frame work is the precomputed table applied to the frame: build a map once per
//! image size and gaze point ([`LogPolarMap::shifted`] moves a full-resolution map by whole
//! pixels without rebuilding it).

mod apply;
mod box_pyramid;
mod inverse;
mod quads;
mod sample;
#[cfg(test)]
mod tests;

use crate::{FoveaError, Result};
use ocellus_image::{Backend, Plane};
use sample::{contiguous, out_slice};
use std::f64::consts::TAU;

/// Parameters of a log-polar map.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogPolarConfig {
    /// Log rings R between `fovea_radius` and `max_radius`.
    pub rings: usize,
    /// Sectors S over the full turn.
    pub sectors: usize,
    /// Linear rings F inside the fovea (0 leaves the fovea unsampled).
    pub fovea_rings: usize,
    /// Fovea radius rho_0, pixels (> 0).
    pub fovea_radius: f64,
    /// Outer radius rho_max, pixels (> rho_0).
    pub max_radius: f64,
    /// Gaze point (x, y), pixels, pixel centres at integers. It may lie anywhere; fields
    /// outside the image report 0 and are flagged in [`LogPolarMap::coverage`].
    pub centre: [f64; 2],
    /// Coarsest box-pyramid level fields may read (0: full resolution only; at most 4).
    pub max_level: usize,
    /// Least texels across a field's smaller side when choosing its pyramid level (>= 1;
    /// larger is sharper and slower).
    pub min_field_texels: f64,
    /// The shape of the receptive fields.
    pub fields: Fields,
    /// Which build of the byte fast paths' kernels runs (`auto`: the fastest this CPU has).
    #[serde(default)]
    pub backend: Backend,
}

/// The shape of the receptive fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Fields {
    /// Each cell averages the bilinear image over exactly its annular sector (about 6-13
    /// table entries per cell): the most faithful, for analysis.
    Area,
    /// Each cell reads the box pyramid level whose texels are as large as the cell, with one
    /// bilinear sample at the cell's centroid: an overlapping, smooth field of about the
    /// cell's size (box of the level convolved with a tent), exactly 4 table entries per cell.
    /// The fast default (mipmapping, Williams 1983).
    Pyramid,
}

impl LogPolarConfig {
    /// 128 rings x 128 sectors about the image centre, rho_max half the smaller side,
    /// rho_0 = rho_max / 60 (at least 2 px), one fovea ring per pixel of rho_0, pyramid up to
    /// level 4, [`Fields::Pyramid`] fields one texel across.
    pub fn for_image(width: usize, height: usize) -> Self {
        let max_radius = (width.min(height) as f64 / 2.0).max(2.0);
        let fovea_radius = (max_radius / 60.0).max(2.0).min(max_radius / 2.0);
        Self {
            rings: 128,
            sectors: 128,
            fovea_rings: fovea_radius.round().max(1.0) as usize,
            fovea_radius,
            max_radius,
            centre: [(width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0],
            max_level: 4,
            min_field_texels: 1.0,
            fields: Fields::Pyramid,
            backend: Backend::Auto,
        }
    }

    /// The ring ratio a = (rho_max / rho_0)^(1 / R): a scaling by a shifts the log rings by one.
    pub fn ring_ratio(&self) -> f64 {
        (self.max_radius / self.fovea_radius).powf(1.0 / self.rings as f64)
    }

    fn check(&self) -> Result<()> {
        let bad = |why: String| Err(FoveaError::Invalid(why));
        if self.rings == 0 || self.sectors == 0 {
            return bad(format!("{} rings x {} sectors: need at least one of each", self.rings, self.sectors));
        }
        if self.rings > 65_536 || self.sectors > 65_536 || self.fovea_rings > 65_536 {
            return bad(format!("{} rings, {} sectors: at most 65536", self.rings, self.sectors));
        }
        let cells = (self.rings + self.fovea_rings) * self.sectors;
        if cells > 1 << 24 {
            return bad(format!("{cells} cells (rings x sectors): at most 2^24"));
        }
        if !(self.fovea_radius.is_finite() && self.fovea_radius > 0.0) {
            return bad(format!("fovea radius {} px must be positive", self.fovea_radius));
        }
        if !(self.max_radius.is_finite() && self.max_radius > self.fovea_radius && self.max_radius < 1e6) {
            return bad(format!(
                "outer radius {} px must exceed the fovea radius {} px",
                self.max_radius, self.fovea_radius
            ));
        }
        if !(self.centre[0].is_finite() && self.centre[1].is_finite()) {
            return bad(format!("gaze point {:?}", self.centre));
        }
        if self.max_level > 4 {
            return bad(format!("pyramid level {} (at most 4)", self.max_level));
        }
        if !(self.min_field_texels.is_finite() && self.min_field_texels >= 1.0) {
            return bad(format!("min_field_texels {} (at least 1)", self.min_field_texels));
        }
        Ok(())
    }
}

/// Buffers reused from frame to frame (the box pyramid).
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    pyramid: Vec<f32>,
    row: Vec<f32>,
    pyramid16: Vec<u16>,
    pyramid_rgb: Vec<u16>,
    planes: Vec<u8>,
    channels: Vec<f32>,
}

/// A log-polar map for one image size and one gaze point: the sparse weight table and what
/// is needed to apply it. Build once, apply to every frame.
#[derive(Clone, Debug)]
pub struct LogPolarMap {
    cfg: LogPolarConfig,
    width: usize,
    height: usize,
    rows: usize,
    /// Entries of cell c: `start[c]..start[c + 1]`.
    start: Vec<u32>,
    /// Pyramid level of each cell's entries.
    level: Vec<u8>,
    /// Texel index: `y * width + x` at level 0; the pyramid buffer index above.
    offset: Vec<u32>,
    weight: Vec<f32>,
    /// [`Fields::Pyramid`] cells: index of the top-left texel of the bilinear quad and the
    /// fractions (fx, fy) towards the next column and row.
    quad_base: Vec<u32>,
    quad_fx: Vec<f32>,
    quad_fy: Vec<f32>,
    /// [`Fields::Pyramid`] cells whose centroid is off the image (their quad reads texel 0
    /// and their output is set to 0).
    invalid: Vec<u32>,
    /// [`Fields::Pyramid`] cells of each level, when the levels do not decrease from cell to
    /// cell (always, for the ring-major order): the grey fast path runs level by level.
    level_ranges: Option<Vec<std::ops::Range<usize>>>,
    /// The largest quad base of each level's range (whether its gathers stay in bounds).
    level_max_base: Vec<usize>,
    coverage: Vec<f32>,
    /// Start of each level in the pyramid buffer (in texels), levels 1..=levels.
    level_base: Vec<usize>,
    levels: usize,
    /// Level-0 pixel rectangle [x0, y0, x1, y1) the pyramid levels are computed over
    /// (what the fields read, aligned to the coarsest level).
    pyramid_rect: [usize; 4],
    /// Level-0 pixel rectangle [x0, y0, x1, y1) of everything the quads read at any level.
    read_rect: [usize; 4],
    /// Level-0 pixel rectangle [x0, y0, x1, y1) the level-0 quads read (their gathers read up
    /// to 2 bytes more to the right).
    level0_rect: [usize; 4],
}

/// Size of pyramid level `l` of a `w` x `h` image (level 0 is the image).
fn level_size(w: usize, h: usize, l: usize) -> (usize, usize) {
    (w >> l, h >> l)
}

impl LogPolarMap {
    /// Builds the weight table of `cfg` for `width` x `height` images.
    pub fn new(cfg: &LogPolarConfig, width: usize, height: usize) -> Result<Self> {
        cfg.check()?;
        if width == 0 || height == 0 || width.checked_mul(height).is_none_or(|n| n >= u32::MAX as usize / 4) {
            return Err(FoveaError::Invalid(format!("image size {width}x{height}")));
        }
        let rows = cfg.fovea_rings + cfg.rings;
        let cells = rows * cfg.sectors;
        // Levels that exist: each must be at least one texel.
        let mut top = 0;
        while top < cfg.max_level
            && level_size(width, height, top + 1).0 >= 1
            && level_size(width, height, top + 1).1 >= 1
        {
            top += 1;
        }
        let mut level_base = vec![0usize; top + 1];
        let mut total = 0;
        for l in 1..=top {
            level_base[l] = total;
            let (lw, lh) = level_size(width, height, l);
            total += lw * lh;
        }
        let mut map = Self {
            cfg: *cfg,
            width,
            height,
            rows,
            start: Vec::with_capacity(cells + 1),
            level: Vec::with_capacity(cells),
            offset: Vec::new(),
            weight: Vec::new(),
            quad_base: Vec::new(),
            quad_fx: Vec::new(),
            quad_fy: Vec::new(),
            invalid: Vec::new(),
            level_ranges: None,
            level_max_base: Vec::new(),
            coverage: Vec::with_capacity(cells),
            level_base,
            levels: 0,
            pyramid_rect: [0, 0, 0, 0],
            read_rect: [0, 0, 0, 0],
            level0_rect: [0, 0, 0, 0],
        };
        map.start.push(0);
        let mut acc: Vec<(u32, f32)> = Vec::new();
        let dt = TAU / cfg.sectors as f64;
        for row in 0..rows {
            let (r0, r1) = map.row_radii(row);
            let (dr, arc) = (r1 - r0, 0.5 * (r0 + r1) * dt);
            let size = dr.min(arc);
            let mut l = 0;
            while l < top && (1usize << (l + 1)) as f64 * cfg.min_field_texels <= size {
                l += 1;
            }
            let t = (1usize << l) as f64;
            let (lw, lh) = level_size(width, height, l);
            // About two samples per texel each way (at least 2): the midpoint rule on a
            // bilinear surface is then accurate to a small fraction of a grey level.
            let nr = ((2.0 * dr / t).ceil() as usize).clamp(2, 64);
            let nt = ((2.0 * arc / t).ceil() as usize).clamp(2, 64);
            let half = (t - 1.0) / 2.0;
            for sector in 0..cfg.sectors {
                acc.clear();
                if cfg.fields == Fields::Pyramid {
                    map.push_centroid_cell(row, sector, l, lw, lh);
                    continue;
                }
                let t0 = sector as f64 * dt;
                let (mut inside, mut all) = (0.0f64, 0.0f64);
                for m in 0..nr {
                    let r = r0 + (m as f64 + 0.5) * dr / nr as f64;
                    for n in 0..nt {
                        let (s, c) = (t0 + (n as f64 + 0.5) * dt / nt as f64).sin_cos();
                        let x = (cfg.centre[0] + r * c - half) / t;
                        let y = (cfg.centre[1] + r * s - half) / t;
                        all += r;
                        let (x0, y0) = (x.floor(), y.floor());
                        let (fx, fy) = (x - x0, y - y0);
                        for (dx, dy, w) in [
                            (0, 0, (1.0 - fx) * (1.0 - fy)),
                            (1, 0, fx * (1.0 - fy)),
                            (0, 1, (1.0 - fx) * fy),
                            (1, 1, fx * fy),
                        ] {
                            let (xi, yi) = (x0 + dx as f64, y0 + dy as f64);
                            if w <= 0.0 || xi < 0.0 || yi < 0.0 || xi >= lw as f64 || yi >= lh as f64 {
                                continue;
                            }
                            inside += r * w;
                            acc.push(((yi as usize * lw + xi as usize) as u32, (r * w) as f32));
                        }
                    }
                }
                acc.sort_unstable_by_key(|e| e.0);
                let mut merged: Vec<(u32, f32)> = Vec::with_capacity(acc.len());
                for &(o, w) in &acc {
                    match merged.last_mut() {
                        Some(last) if last.0 == o => last.1 += w,
                        _ => merged.push((o, w)),
                    }
                }
                // Entries below 0.1 % of the field add nothing visible and cost a load each.
                let sum: f32 = merged.iter().map(|e| e.1).sum();
                merged.retain(|e| e.1 > 1e-3 * sum);
                let kept: f32 = merged.iter().map(|e| e.1).sum();
                let base = if l == 0 { 0 } else { map.level_base[l] };
                for (o, w) in merged {
                    map.offset.push((base + o as usize) as u32);
                    map.weight.push(w / kept);
                }
                map.start.push(map.offset.len() as u32);
                map.level.push(l as u8);
                map.coverage.push(if all > 0.0 { (inside / all) as f32 } else { 0.0 });
                if kept > 0.0 {
                    map.levels = map.levels.max(l);
                }
            }
        }
        map.pyramid_rect = map.rect_read();
        map.read_rect = map.pyramid_rect;
        if map.levels == 0 {
            map.read_rect = [usize::MAX, usize::MAX, 0, 0];
        }
        let mut l0 = [usize::MAX, usize::MAX, 0, 0];
        for (&b, &l) in map.quad_base.iter().zip(&map.level) {
            if l == 0 {
                let (x, y) = (b as usize % width, b as usize / width);
                l0 = [l0[0].min(x), l0[1].min(y), l0[2].max((x + 4).min(width)), l0[3].max((y + 2).min(height))];
                let r = &mut map.read_rect;
                *r = [r[0].min(x), r[1].min(y), r[2].max((x + 2).min(width)), r[3].max((y + 2).min(height))];
            }
        }
        map.level0_rect = if l0[0] == usize::MAX { [0, 0, 0, 0] } else { l0 };
        if map.read_rect[0] == usize::MAX {
            map.read_rect = [0, 0, 0, 0];
        }
        if cfg.fields == Fields::Pyramid && map.level.windows(2).all(|p| p[0] <= p[1]) {
            let mut ranges = vec![0..0; map.levels + 1];
            for (l, r) in ranges.iter_mut().enumerate() {
                let a = map.level.partition_point(|&v| (v as usize) < l);
                let b = map.level.partition_point(|&v| (v as usize) <= l);
                *r = a..b;
            }
            // Cells above `levels` exist only when they read nothing (all invalid).
            if ranges.last().map_or(0, |r| r.end) == map.level.len() {
                map.level_max_base = ranges
                    .iter()
                    .map(|r| map.quad_base[r.clone()].iter().map(|&b| b as usize).max().unwrap_or(0))
                    .collect();
                map.level_ranges = Some(ranges);
            }
        }
        Ok(map)
    }

    /// The level-0 rectangle covering every pyramid texel the table reads, aligned to the
    /// coarsest level used.
    fn rect_read(&self) -> [usize; 4] {
        if self.levels == 0 {
            return [0, 0, 0, 0];
        }
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for c in 0..self.level.len() {
            let l = self.level[c] as usize;
            if l == 0 {
                continue;
            }
            let (lw, _) = level_size(self.width, self.height, l);
            for &o in &self.offset[self.start[c] as usize..self.start[c + 1] as usize] {
                let i = o as usize - self.level_base[l];
                let (x, y) = (i % lw, i / lw);
                x0 = x0.min(x << l);
                y0 = y0.min(y << l);
                x1 = x1.max((x + 1) << l);
                y1 = y1.max((y + 1) << l);
            }
        }
        for (c, (&b, &l)) in self.quad_base.iter().zip(&self.level).enumerate() {
            let l = l as usize;
            if l == 0 || self.invalid.binary_search(&(c as u32)).is_ok() {
                continue;
            }
            let (lw, _) = level_size(self.width, self.height, l);
            let i = b as usize - self.level_base[l];
            let (x, y) = (i % lw, i / lw);
            x0 = x0.min(x << l);
            y0 = y0.min(y << l);
            x1 = x1.max((x + 2) << l);
            y1 = y1.max((y + 2) << l);
        }
        if x0 == usize::MAX {
            return [0, 0, 0, 0];
        }
        let a = 1usize << self.levels;
        [x0 / a * a, y0 / a * a, x1.div_ceil(a) * a, y1.div_ceil(a) * a]
    }

    /// The same map with the gaze point moved by whole pixels (dx, dy), without rebuilding
    /// the table: possible when every field reads full-resolution pixels (`max_level` 0 or
    /// fields too small for the pyramid) and the fields lie inside the image before and after
    /// the move. `None` otherwise (build a new map then).
    pub fn shifted(&self, dx: i64, dy: i64) -> Option<LogPolarMap> {
        let delta = self.move_delta(dx, dy)? as i64;
        let mut out = self.clone();
        out.cfg.centre = [self.cfg.centre[0] + dx as f64, self.cfg.centre[1] + dy as f64];
        for o in out.offset.iter_mut().chain(out.quad_base.iter_mut()) {
            *o = (*o as i64 + delta) as u32;
        }
        Some(out)
    }

    /// The change of every full-resolution pixel index when the gaze point moves by whole
    /// pixels (dx, dy), when the move keeps the table valid (see [`Self::shifted`]).
    fn move_delta(&self, dx: i64, dy: i64) -> Option<isize> {
        let inside = |cx: f64, cy: f64| {
            let r = self.cfg.max_radius + 2.0;
            cx - r >= 0.0 && cy - r >= 0.0 && cx + r <= (self.width - 1) as f64 && cy + r <= (self.height - 1) as f64
        };
        let [cx, cy] = self.cfg.centre;
        let movable = self.levels == 0 && self.invalid.is_empty() && inside(cx, cy);
        (movable && inside(cx + dx as f64, cy + dy as f64)).then(|| (dy * self.width as i64 + dx) as isize)
    }

    /// [`Self::sample_grey_into`] with the gaze point moved by whole pixels (dx, dy): the same
    /// table read at an offset, neither rebuilt nor copied (as [`Self::shifted`] copies it).
    /// `Ok(false)`, and nothing written, where [`Self::shifted`] gives `None`.
    pub fn sample_grey_moved_into(
        &self,
        img: &Plane<u8>,
        (dx, dy): (i64, i64),
        scratch: &mut Scratch,
        out: &mut Plane<f32>,
    ) -> Result<bool> {
        self.check_size(img.width(), img.height())?;
        let Some(delta) = self.move_delta(dx, dy) else { return Ok(false) };
        out.resize(self.cfg.sectors, self.rows);
        self.apply::<u8, 1>(&contiguous(img), delta, scratch, out_slice(out));
        Ok(true)
    }

    /// A [`Fields::Pyramid`] cell: one bilinear sample of level `l` (`lw` x `lh` texels) at
    /// the centroid of the cell's annular sector (radius `2/3 (r1^3 - r0^3) / (r1^2 - r0^2)
    /// sinc(dt / 2)` along the middle angle).
    fn push_centroid_cell(&mut self, row: usize, sector: usize, l: usize, lw: usize, lh: usize) {
        let (r0, r1) = self.row_radii(row);
        let dt = TAU / self.cfg.sectors as f64;
        let rc = if r1 > r0 { 2.0 / 3.0 * (r1.powi(3) - r0.powi(3)) / (r1 * r1 - r0 * r0) } else { r0 };
        let rc = rc * (dt / 2.0).sin() / (dt / 2.0);
        let (s, c) = self.sector_angle(sector).sin_cos();
        let t = (1usize << l) as f64;
        let half = (t - 1.0) / 2.0;
        let x = (self.cfg.centre[0] + rc * c - half) / t;
        let y = (self.cfg.centre[1] + rc * s - half) / t;
        // Texels beyond the level's edge are read as the edge (clamped), so that a cell half
        // off the image still gets a value; cells whose centroid is off the image get none.
        let base = if l == 0 { 0 } else { self.level_base[l] };
        let inside = x > -0.5 && y > -0.5 && x < lw as f64 - 0.5 && y < lh as f64 - 0.5 && lw >= 2 && lh >= 2;
        if inside {
            // The quad's top-left texel stays one short of the last row and column, so that
            // the quad is always 2x2 inside the level (the fraction may then reach 1).
            let (xc, yc) = (x.clamp(0.0, (lw - 1) as f64), y.clamp(0.0, (lh - 1) as f64));
            let (x0, y0) = ((xc.floor() as usize).min(lw - 2), (yc.floor() as usize).min(lh - 2));
            self.quad_base.push((base + y0 * lw + x0) as u32);
            self.quad_fx.push((xc - x0 as f64) as f32);
            self.quad_fy.push((yc - y0 as f64) as f32);
            self.levels = self.levels.max(l);
        } else {
            self.invalid.push(self.quad_base.len() as u32);
            self.quad_base.push(base as u32);
            self.quad_fx.push(0.0);
            self.quad_fy.push(0.0);
        }
        self.start.push(self.offset.len() as u32);
        self.level.push(l as u8);
        self.coverage.push(if inside { 1.0 } else { 0.0 });
    }

    /// The configuration.
    pub fn config(&self) -> &LogPolarConfig {
        &self.cfg
    }

    /// Rows of the cortical image: fovea rings, then log rings.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Columns of the cortical image (sectors).
    pub fn sectors(&self) -> usize {
        self.cfg.sectors
    }

    /// The image size the map was built for.
    pub fn image_size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Inner and outer radius of cortical row `row`, pixels.
    pub fn row_radii(&self, row: usize) -> (f64, f64) {
        let (f, rho0) = (self.cfg.fovea_rings, self.cfg.fovea_radius);
        if row < f {
            (rho0 * row as f64 / f as f64, rho0 * (row + 1) as f64 / f as f64)
        } else {
            let a = self.cfg.ring_ratio();
            let i = (row - f) as f64;
            (rho0 * a.powf(i), rho0 * a.powf(i + 1.0))
        }
    }

    /// Angle of the middle of sector `sector`, radians from +x towards +y.
    pub fn sector_angle(&self, sector: usize) -> f64 {
        (sector as f64 + 0.5) * TAU / self.cfg.sectors as f64
    }

    /// Fraction of each cell's field inside the image (row-major, rows x sectors); cells at 0
    /// report 0.
    pub fn coverage(&self) -> &[f32] {
        &self.coverage
    }

    /// Input pixels per cortical cell: the data compression of the map.
    pub fn compression_ratio(&self) -> f64 {
        (self.width * self.height) as f64 / (self.rows * self.cfg.sectors) as f64
    }

    /// Entries of the weight table (the per-frame work, in texel reads per channel).
    pub fn table_entries(&self) -> usize {
        self.offset.len() + 4 * self.quad_base.len()
    }
}
