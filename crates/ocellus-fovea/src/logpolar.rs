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

use crate::{FoveaError, Result};
use ocellus_image::Plane;
use std::f64::consts::TAU;

/// Parameters of a log-polar map.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
        if width == 0 || height == 0 || width.checked_mul(height).map_or(true, |n| n >= u32::MAX as usize / 4) {
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
        let inside = |cx: f64, cy: f64| {
            let r = self.cfg.max_radius + 2.0;
            cx - r >= 0.0 && cy - r >= 0.0 && cx + r <= (self.width - 1) as f64 && cy + r <= (self.height - 1) as f64
        };
        let [cx, cy] = self.cfg.centre;
        let (nx, ny) = (cx + dx as f64, cy + dy as f64);
        if self.levels != 0 || !inside(cx, cy) || !inside(nx, ny) {
            return None;
        }
        let delta = dy * self.width as i64 + dx;
        let mut out = self.clone();
        out.cfg.centre = [nx, ny];
        for o in out.offset.iter_mut() {
            *o = (*o as i64 + delta) as u32;
        }
        if !out.invalid.is_empty() {
            return None;
        }
        for o in out.quad_base.iter_mut() {
            *o = (*o as i64 + delta) as u32;
        }
        Some(out)
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

    fn check_size(&self, w: usize, h: usize) -> Result<()> {
        if (w, h) != (self.width, self.height) {
            return Err(FoveaError::Size { got_w: w, got_h: h, want_w: self.width, want_h: self.height });
        }
        Ok(())
    }

    /// The cortical image of a grey image (grey levels as given: 0..255), `sectors` wide and
    /// `rows` high.
    pub fn sample_grey(&self, img: &Plane<u8>) -> Result<Plane<f32>> {
        let mut out = Plane::new(self.cfg.sectors, self.rows);
        self.sample_grey_into(img, &mut Scratch::default(), &mut out)?;
        Ok(out)
    }

    /// [`Self::sample_grey`] into reused buffers (`out` is resized).
    pub fn sample_grey_into(&self, img: &Plane<u8>, scratch: &mut Scratch, out: &mut Plane<f32>) -> Result<()> {
        self.check_size(img.width(), img.height())?;
        out.resize(self.cfg.sectors, self.rows);
        let src = contiguous(img);
        let o = out_slice(out);
        if self.cfg.fields != Fields::Pyramid || !self.apply_grey_pyramid(&src, scratch, o) {
            self.apply::<u8, 1>(&src, scratch, o);
        }
        Ok(())
    }

    /// The cortical image of a float image (any units; e.g. a magnitude spectrum).
    pub fn sample_f32(&self, img: &Plane<f32>) -> Result<Plane<f32>> {
        self.check_size(img.width(), img.height())?;
        let mut out = Plane::new(self.cfg.sectors, self.rows);
        let src = contiguous(img);
        self.apply::<f32, 1>(&src, &mut Scratch::default(), out_slice(&mut out));
        Ok(out)
    }

    /// The cortical image of an RGB image: three planes (r, g, b), grey levels 0..255.
    pub fn sample_rgb(&self, img: &Plane<[u8; 3]>) -> Result<[Plane<f32>; 3]> {
        let mut out = vec![0.0f32; 3 * self.rows * self.cfg.sectors];
        self.sample_rgb_into(img, &mut Scratch::default(), &mut out)?;
        let n = self.rows * self.cfg.sectors;
        let plane = |c: usize| {
            Plane::from_vec(self.cfg.sectors, self.rows, out[c * n..(c + 1) * n].to_vec()).unwrap_or_default()
        };
        Ok([plane(0), plane(1), plane(2)])
    }

    /// [`Self::sample_rgb`] into reused buffers: `out` is resized to `3 rows sectors`: the
    /// red cortical image, then the green, then the blue (each row-major, `sectors` wide).
    pub fn sample_rgb_into(&self, img: &Plane<[u8; 3]>, scratch: &mut Scratch, out: &mut Vec<f32>) -> Result<()> {
        self.check_size(img.width(), img.height())?;
        let cells = self.rows * self.cfg.sectors;
        out.resize(3 * cells, 0.0);
        let src = contiguous(img);
        let flat: &[u8] = src.as_flattened();
        if self.cfg.fields == Fields::Pyramid && self.apply_rgb_pyramid(flat, scratch, out) {
            return Ok(());
        }
        let mut mixed = std::mem::take(&mut scratch.channels);
        mixed.resize(3 * cells, 0.0);
        self.apply::<u8, 3>(flat, scratch, &mut mixed);
        for (c, v) in mixed.chunks_exact(3).enumerate() {
            (out[c], out[cells + c], out[2 * cells + c]) = (v[0], v[1], v[2]);
        }
        scratch.channels = mixed;
        Ok(())
    }

    /// Builds the box pyramid (means of 2^l x 2^l pixels) of `src` (C interleaved channels)
    /// up to the coarsest level a field reads, then applies the table.
    fn apply<T: Texel, const C: usize>(&self, src: &[T], scratch: &mut Scratch, out: &mut [f32]) {
        let top = self.levels;
        if top > 0 {
            let (w, h) = (self.width, self.height);
            let total = self.level_base[top] + level_size(w, h, top).0 * level_size(w, h, top).1;
            scratch.pyramid.resize(total * C, 0.0);
            let [rx0, ry0, rx1, ry1] = self.pyramid_rect;
            for l in 1..=top {
                let (pw, _) = level_size(w, h, l - 1);
                let (lw, lh) = level_size(w, h, l);
                // Texels of level l inside the rectangle.
                let (tx0, ty0) = (rx0 >> l, ry0 >> l);
                let (tx1, ty1) = ((rx1 >> l).min(lw), (ry1 >> l).min(lh));
                if tx1 <= tx0 || ty1 <= ty0 {
                    continue;
                }
                let (lo, hi) = scratch.pyramid.split_at_mut(self.level_base[l] * C);
                let dst = &mut hi[..lw * lh * C];
                if l == 1 {
                    halve::<T, C>(src, pw, dst, lw, [tx0, ty0, tx1, ty1], &mut scratch.row);
                } else {
                    let prev = &lo[self.level_base[l - 1] * C..];
                    halve::<f32, C>(prev, pw, dst, lw, [tx0, ty0, tx1, ty1], &mut scratch.row);
                }
            }
        }
        let pyr = &scratch.pyramid;
        if self.cfg.fields == Fields::Pyramid {
            self.apply_quads::<T, C>(src, pyr, out);
            return;
        }
        for (c, o) in out.chunks_exact_mut(C).enumerate() {
            let (s, e) = (self.start[c] as usize, self.start[c + 1] as usize);
            let (offs, ws) = (&self.offset[s..e], &self.weight[s..e]);
            let mut acc = [0.0f32; C];
            if self.level[c] == 0 {
                for (&i, &w) in offs.iter().zip(ws) {
                    let i = i as usize * C;
                    for ch in 0..C {
                        acc[ch] += w * src[i + ch].into();
                    }
                }
            } else {
                for (&i, &w) in offs.iter().zip(ws) {
                    let i = i as usize * C;
                    for ch in 0..C {
                        acc[ch] += w * pyr[i + ch];
                    }
                }
            }
            o.copy_from_slice(&acc);
        }
    }

    /// The [`Fields::Pyramid`] table: one bilinear quad per cell.
    fn apply_quads<T: Texel, const C: usize>(&self, src: &[T], pyr: &[f32], out: &mut [f32]) {
        let row_step: Vec<usize> = (0..=self.levels).map(|l| level_size(self.width, self.height, l).0 * C).collect();
        for ((((o, &b), &fx), &fy), &l) in
            out.chunks_exact_mut(C).zip(&self.quad_base).zip(&self.quad_fx).zip(&self.quad_fy).zip(&self.level)
        {
            let (i, dy) = (b as usize * C, row_step.get(l as usize).copied().unwrap_or(0));
            let last = i + dy + 2 * C - 1;
            let in_bounds = if l == 0 { last < src.len() } else { last < pyr.len() };
            if !in_bounds {
                o.fill(0.0);
                continue;
            }
            for ch in 0..C {
                // SAFETY: the quad's largest index, `last`, was checked just above.
                let (p00, p01, p10, p11) = unsafe {
                    if l == 0 {
                        (
                            (*src.get_unchecked(i + ch)).into(),
                            (*src.get_unchecked(i + C + ch)).into(),
                            (*src.get_unchecked(i + dy + ch)).into(),
                            (*src.get_unchecked(i + dy + C + ch)).into(),
                        )
                    } else {
                        (
                            *pyr.get_unchecked(i + ch),
                            *pyr.get_unchecked(i + C + ch),
                            *pyr.get_unchecked(i + dy + ch),
                            *pyr.get_unchecked(i + dy + C + ch),
                        )
                    }
                };
                let top = p00 + fx * (p01 - p00);
                let bot = p10 + fx * (p11 - p10);
                o[ch] = top + fy * (bot - top);
            }
        }
        self.zero_invalid::<C>(out);
    }

    fn zero_invalid<const C: usize>(&self, out: &mut [f32]) {
        for &c in &self.invalid {
            if let Some(o) = out.get_mut(c as usize * C..c as usize * C + C) {
                o.fill(0.0);
            }
        }
    }

    /// Grey images with [`Fields::Pyramid`]: the pyramid as exact u16 box sums (a level-l
    /// texel holds the sum of 4^l pixels; up to level 4 that fits), then each level's cells
    /// as one run of bilinear quads, 8 cells per step with AVX2 gathers where the CPU has
    /// them. Returns false (nothing done) when the map does not allow it.
    fn apply_grey_pyramid(&self, src: &[u8], scratch: &mut Scratch, out: &mut [f32]) -> bool {
        if self.level_ranges.is_none() || src.len() < self.width * self.height || out.len() < self.quad_base.len() {
            return false;
        }
        let mut pyr = std::mem::take(&mut scratch.pyramid16);
        pyr.resize(self.pyramid_len(), 0);
        self.grey_levels(Some(src), &mut pyr);
        self.grey_quads([src], [&pyr], [out]);
        scratch.pyramid16 = pyr;
        true
    }

    /// Texels of level `l` inside the pyramid rectangle: [x0, y0, x1, y1), or `None`.
    fn level_rect(&self, l: usize) -> Option<[usize; 4]> {
        let (lw, lh) = level_size(self.width, self.height, l);
        let [rx0, ry0, rx1, ry1] = self.pyramid_rect;
        let r = [rx0 >> l, ry0 >> l, (rx1 >> l).min(lw), (ry1 >> l).min(lh)];
        (r[2] > r[0] && r[3] > r[1]).then_some(r)
    }

    /// Elements of the u16 pyramid buffer (all levels).
    fn pyramid_len(&self) -> usize {
        let top = self.levels;
        if top == 0 {
            return 0;
        }
        let (lw, lh) = level_size(self.width, self.height, top);
        self.level_base[top] + lw * lh
    }

    /// The u16 box-sum pyramid levels: level 1 from `level0` when given (else it is already in
    /// `pyr`), then each level from the one below.
    fn grey_levels(&self, level0: Option<&[u8]>, pyr: &mut [u16]) {
        let (w, h) = (self.width, self.height);
        if pyr.len() < self.pyramid_len() {
            return;
        }
        for l in 1..=self.levels {
            let Some(rect) = self.level_rect(l) else { continue };
            let (pw, _) = level_size(w, h, l - 1);
            let (lw, lh) = level_size(w, h, l);
            let (lo, hi) = pyr.split_at_mut(self.level_base[l]);
            let dst = &mut hi[..lw * lh];
            if l == 1 {
                if let Some(src) = level0 {
                    sum4(src, pw, dst, lw, rect);
                }
            } else {
                sum4(&lo[self.level_base[l - 1]..], pw, dst, lw, rect);
            }
        }
    }

    /// Every cell's quad, level by level; sums at level l are scaled by 4^-l.
    fn grey_quads<const K: usize>(&self, level0: [&[u8]; K], pyr: [&[u16]; K], mut out: [&mut [f32]; K]) {
        let Some(ranges) = &self.level_ranges else { return };
        for (l, r) in ranges.iter().enumerate() {
            if r.is_empty() || out.iter().any(|o| o.len() < r.end) {
                continue;
            }
            let (lw, _) = level_size(self.width, self.height, l);
            let scale = 1.0 / (1u32 << (2 * l)) as f32;
            let (b, fx, fy) = (&self.quad_base[r.clone()], &self.quad_fx[r.clone()], &self.quad_fy[r.clone()]);
            let b = (b, self.level_max_base.get(l).copied().unwrap_or(usize::MAX));
            let o: [&mut [f32]; K] = {
                let mut it = out.iter_mut().map(|o| &mut o[r.clone()]);
                std::array::from_fn(|_| it.next().unwrap_or(&mut []))
            };
            if l == 0 {
                quads(level0, lw, b, fx, fy, 1.0, o);
            } else {
                quads(pyr, lw, b, fx, fy, scale, o);
            }
        }
        for o in out.iter_mut() {
            self.zero_invalid::<1>(o);
        }
    }

    /// RGB images with [`Fields::Pyramid`]: level 1 of the three channels in one pass over
    /// the interleaved pixels, the full-resolution channels split out only where level-0
    /// fields read, then the grey levels and quads per channel. Returns false (nothing done)
    /// when the map does not allow it.
    fn apply_rgb_pyramid(&self, flat: &[u8], scratch: &mut Scratch, out: &mut [f32]) -> bool {
        let (w, h) = (self.width, self.height);
        let (n, cells) = (w * h, self.quad_base.len());
        if self.level_ranges.is_none() || flat.len() < 3 * n || out.len() < 3 * cells {
            return false;
        }
        // Planes `n + 320` bytes apart: whole multiples of 4 KiB (640x480 is 75 x 4 KiB) make
        // the three stores per pixel alias.
        let pitch = n + 320;
        let mut planes = std::mem::take(&mut scratch.planes);
        planes.resize(3 * pitch, 0);
        let plen = self.pyramid_len();
        // Its own buffer: sharing the grey one would zero-fill two thirds of it on every
        // switch between grey and RGB frames.
        let mut pyr = std::mem::take(&mut scratch.pyramid_rgb);
        pyr.resize(3 * plen, 0);
        {
            let [x0, y0, x1, y1] = self.level0_rect;
            let (r, gb) = planes.split_at_mut(pitch);
            let (g, b) = gb.split_at_mut(pitch);
            for y in y0..y1 {
                let span = y * w + x0..y * w + x1;
                deinterleave(
                    &flat[3 * span.start..3 * span.end],
                    &mut r[span.clone()],
                    &mut g[span.clone()],
                    &mut b[span],
                );
            }
        }
        if let Some([x0, y0, x1, y1]) = self.level_rect(1).filter(|_| self.levels >= 1) {
            let lw = level_size(w, h, 1).0;
            let (pr, pgb) = pyr.split_at_mut(plen);
            let (pg, pb) = pgb.split_at_mut(plen);
            let base = self.level_base[1];
            for y in y0..y1 {
                let a = &flat[3 * (2 * y * w + 2 * x0)..3 * (2 * y * w + 2 * x1)];
                let b = &flat[3 * ((2 * y + 1) * w + 2 * x0)..3 * ((2 * y + 1) * w + 2 * x1)];
                let span = base + y * lw + x0..base + y * lw + x1;
                sum4_rgb_row(a, b, &mut pr[span.clone()], &mut pg[span.clone()], &mut pb[span]);
            }
        }
        for p in pyr.chunks_exact_mut(plen.max(1)).take(3) {
            self.grey_levels(None, p);
        }
        let (o0, o12) = out.split_at_mut(cells);
        let (o1, o2) = o12.split_at_mut(cells);
        let level0 = [&planes[..n], &planes[pitch..pitch + n], &planes[2 * pitch..2 * pitch + n]];
        let p = [&pyr[..plen], &pyr[plen..2 * plen], &pyr[2 * plen..3 * plen]];
        self.grey_quads(level0, p, [o0, o1, &mut o2[..cells]]);
        scratch.planes = planes;
        scratch.pyramid_rgb = pyr;
        true
    }

    /// Back to a `width` x `height` Cartesian image for display: each pixel reads the
    /// cortical image bilinearly (cyclic across sectors) at its own (ring, sector)
    /// coordinates; pixels beyond rho_max (or inside an unsampled fovea) are 0.
    pub fn inverse(&self, cortex: &Plane<f32>) -> Result<Plane<f32>> {
        if cortex.size() != (self.cfg.sectors, self.rows) {
            return Err(FoveaError::Size {
                got_w: cortex.width(),
                got_h: cortex.height(),
                want_w: self.cfg.sectors,
                want_h: self.rows,
            });
        }
        let mut out = Plane::new(self.width, self.height);
        for y in 0..self.height {
            for x in 0..self.width {
                if let Some((row, col)) = self.cortical_coordinates(x as f64, y as f64) {
                    out.set(x, y, self.read_cortex(cortex, row, col));
                }
            }
        }
        Ok(out)
    }

    /// Fractional cortical coordinates (row, column) of image point (x, y), cell centres at
    /// integers; `None` outside rho_max or in an unsampled fovea.
    pub fn cortical_coordinates(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (dx, dy) = (x - self.cfg.centre[0], y - self.cfg.centre[1]);
        let r = dx.hypot(dy);
        let (f, rho0) = (self.cfg.fovea_rings, self.cfg.fovea_radius);
        if r >= self.cfg.max_radius {
            return None;
        }
        let row = if r < rho0 {
            if f == 0 {
                return None;
            }
            r / rho0 * f as f64 - 0.5
        } else {
            f as f64 + (r / rho0).ln() / self.cfg.ring_ratio().ln() - 0.5
        };
        let col = dy.atan2(dx).rem_euclid(TAU) / TAU * self.cfg.sectors as f64 - 0.5;
        Some((row, col))
    }

    fn read_cortex(&self, cortex: &Plane<f32>, row: f64, col: f64) -> f32 {
        let s = self.cfg.sectors as i64;
        let r = row.clamp(0.0, (self.rows - 1) as f64);
        let (r0, c0) = (r.floor(), col.floor());
        let (fr, fc) = ((r - r0) as f32, (col - c0) as f32);
        let r0 = r0 as usize;
        let r1 = (r0 + 1).min(self.rows - 1);
        let c0i = (c0 as i64).rem_euclid(s) as usize;
        let c1i = (c0 as i64 + 1).rem_euclid(s) as usize;
        let top = cortex.get(c0i, r0) + fc * (cortex.get(c1i, r0) - cortex.get(c0i, r0));
        let bot = cortex.get(c0i, r1) + fc * (cortex.get(c1i, r1) - cortex.get(c0i, r1));
        top + fr * (bot - top)
    }

    /// Point-sampled cortical image for comparison (what a plain remap such as OpenCV's
    /// `warpPolar` does): one nearest or bilinear sample at each cell's centre, no area.
    pub fn sample_point_grey(&self, img: &Plane<u8>, bilinear: bool) -> Result<Plane<f32>> {
        self.check_size(img.width(), img.height())?;
        let mut out = Plane::new(self.cfg.sectors, self.rows);
        let (w, h) = (self.width as f64, self.height as f64);
        for row in 0..self.rows {
            let (r0, r1) = self.row_radii(row);
            let r = 0.5 * (r0 + r1);
            for s in 0..self.cfg.sectors {
                let (sn, cs) = self.sector_angle(s).sin_cos();
                let (x, y) = (self.cfg.centre[0] + r * cs, self.cfg.centre[1] + r * sn);
                if x < -0.5 || y < -0.5 || x > w - 0.5 || y > h - 0.5 {
                    continue;
                }
                let v = if bilinear {
                    let xc = x.clamp(0.0, w - 1.0);
                    let yc = y.clamp(0.0, h - 1.0);
                    let (x0, y0) = (xc.floor() as usize, yc.floor() as usize);
                    let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
                    let (ax, ay) = ((xc - x0 as f64) as f32, (yc - y0 as f64) as f32);
                    let g = |xx: usize, yy: usize| img.get(xx, yy) as f32;
                    let top = g(x0, y0) + ax * (g(x1, y0) - g(x0, y0));
                    let bot = g(x0, y1) + ax * (g(x1, y1) - g(x0, y1));
                    top + ay * (bot - top)
                } else {
                    let (xi, yi) = (
                        (x.round().max(0.0) as usize).min(self.width - 1),
                        (y.round().max(0.0) as usize).min(self.height - 1),
                    );
                    img.get(xi, yi) as f32
                };
                out.set(s, row, v);
            }
        }
        Ok(out)
    }
}

/// The pixels as one row-major slice (copied only when the plane has padding).
fn contiguous<T: Copy + Default>(img: &Plane<T>) -> std::borrow::Cow<'_, [T]> {
    match img.as_contiguous() {
        Some(s) => std::borrow::Cow::Borrowed(s),
        None => std::borrow::Cow::Owned(img.to_vec()),
    }
}

fn out_slice(out: &mut Plane<f32>) -> &mut [f32] {
    out.as_contiguous_mut().unwrap_or_default()
}

/// Pixel types the pyramid reads: the sum of two is kept exactly in `Acc`.
trait Texel: Copy + Into<f32> {
    /// Pairwise sum type.
    type Acc: Copy + std::ops::Add<Output = Self::Acc> + Into<f32>;
    fn acc(self) -> Self::Acc;
}

impl Texel for u8 {
    type Acc = u16;
    #[inline(always)]
    fn acc(self) -> u16 {
        self as u16
    }
}

impl Texel for f32 {
    type Acc = f32;
    #[inline(always)]
    fn acc(self) -> f32 {
        self
    }
}

/// One box-pyramid level: texels `rect` = [x0, y0, x1, y1) of `dst` (row length `lw`
/// texels) become the means of 2x2 texels of `src` (row length `sw`), C interleaved channels.
/// Row pairs are summed first (contiguous, vectorized), then column pairs.
fn halve<T: Texel, const C: usize>(
    src: &[T],
    sw: usize,
    dst: &mut [f32],
    lw: usize,
    rect: [usize; 4],
    row: &mut Vec<f32>,
) {
    let [x0, y0, x1, y1] = rect;
    let n = 2 * (x1 - x0) * C;
    row.resize(n, 0.0);
    for y in y0..y1 {
        let a = &src[(2 * y * sw + 2 * x0) * C..][..n];
        let b = &src[((2 * y + 1) * sw + 2 * x0) * C..][..n];
        for ((r, &p), &q) in row.iter_mut().zip(a).zip(b) {
            *r = (p.acc() + q.acc()).into();
        }
        let d = &mut dst[(y * lw + x0) * C..(y * lw + x1) * C];
        for (o, pair) in d.chunks_exact_mut(C).zip(row.chunks_exact(2 * C)) {
            for ch in 0..C {
                o[ch] = 0.25 * (pair[ch] + pair[C + ch]);
            }
        }
    }
}

/// Sources of the grey fast path: u8 pixels (level 0) or u16 box sums.
trait Quad: Copy + Into<f32> {
    /// Whether 8 quads can be read with AVX2 gathers from a buffer of `len` elements with rows
    /// of `lw`: a gather reads 4 bytes at each quad's two rows.
    fn gather_safe(max_base: usize, lw: usize, len: usize) -> bool;
}

impl Quad for u8 {
    fn gather_safe(max_base: usize, lw: usize, len: usize) -> bool {
        max_base + lw + 4 <= len
    }
}

impl Quad for u16 {
    fn gather_safe(max_base: usize, lw: usize, len: usize) -> bool {
        max_base + lw + 2 <= len
    }
}

/// Bilinear quads `src[b], src[b + 1], src[b + lw], src[b + lw + 1]` with fractions
/// (fx, fy), times `scale`, into `out`, for K sources with the same layout at once (the
/// quads' positions are loaded once); `max_base` is the largest of `bases`.
fn quads<T: Quad, const K: usize>(
    src: [&[T]; K],
    lw: usize,
    (bases, max_base): (&[u32], usize),
    fx: &[f32],
    fy: &[f32],
    scale: f32,
    mut out: [&mut [f32]; K],
) {
    let n = out.iter().fold(bases.len().min(fx.len()).min(fy.len()), |n, o| n.min(o.len()));
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if n >= 8
        && src.iter().all(|s| s.len() < i32::MAX as usize && T::gather_safe(max_base, lw, s.len()))
        && is_x86_feature_detected!("avx2")
    {
        // SAFETY: AVX2 detected; every gather reads inside its source (checked just above).
        done = unsafe { quads_avx2(src, lw, &bases[..n], &fx[..n], &fy[..n], scale, &mut out) };
    }
    for (s, o) in src.iter().zip(out.iter_mut()) {
        for k in done..n {
            let b = bases[k] as usize;
            let (Some(&p00), Some(&p01), Some(&p10), Some(&p11)) =
                (s.get(b), s.get(b + 1), s.get(b + lw), s.get(b + lw + 1))
            else {
                o[k] = 0.0;
                continue;
            };
            let (p00, p01, p10, p11): (f32, f32, f32, f32) = (p00.into(), p01.into(), p10.into(), p11.into());
            let top = p00 + fx[k] * (p01 - p00);
            let bot = p10 + fx[k] * (p11 - p10);
            o[k] = scale * (top + fy[k] * (bot - top));
        }
    }
}

/// [`quads`] 8 at a time; returns how many were done (a multiple of 8).
///
/// # Safety
/// AVX2 must be available, each source shorter than 2^31 elements, and for every base b the
/// 4 bytes from element b and from element b + lw must lie inside every source; `fx`, `fy`
/// and every output at least as long as `bases`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn quads_avx2<T: Quad, const K: usize>(
    src: [&[T]; K],
    lw: usize,
    bases: &[u32],
    fx: &[f32],
    fy: &[f32],
    scale: f32,
    out: &mut [&mut [f32]; K],
) -> usize {
    use std::arch::x86_64::*;
    let n = bases.len() / 8 * 8;
    let wide = std::mem::size_of::<T>() == 2;
    // SAFETY (whole body): the caller guarantees the feature and the gathers' bounds; the
    // other loads and stores are within the slices (k + 8 <= n).
    unsafe {
        let row = _mm256_set1_epi32(lw as i32);
        let mask = if wide { _mm256_set1_epi32(0xffff) } else { _mm256_set1_epi32(0xff) };
        let sc = _mm256_set1_ps(scale);
        let split = |v: __m256i| {
            let lo = _mm256_cvtepi32_ps(_mm256_and_si256(v, mask));
            let hi = if wide {
                _mm256_cvtepi32_ps(_mm256_srli_epi32::<16>(v))
            } else {
                _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32::<8>(v), mask))
            };
            (lo, hi)
        };
        let mut k = 0;
        while k < n {
            let idx = _mm256_loadu_si256(bases.as_ptr().add(k) as *const __m256i);
            let below = _mm256_add_epi32(idx, row);
            let x = _mm256_loadu_ps(fx.as_ptr().add(k));
            let y = _mm256_loadu_ps(fy.as_ptr().add(k));
            for c in 0..K {
                let p = src[c].as_ptr() as *const i32;
                let (t, b) = if wide {
                    (_mm256_i32gather_epi32::<2>(p, idx), _mm256_i32gather_epi32::<2>(p, below))
                } else {
                    (_mm256_i32gather_epi32::<1>(p, idx), _mm256_i32gather_epi32::<1>(p, below))
                };
                let ((p00, p01), (p10, p11)) = (split(t), split(b));
                let top = _mm256_add_ps(p00, _mm256_mul_ps(x, _mm256_sub_ps(p01, p00)));
                let bot = _mm256_add_ps(p10, _mm256_mul_ps(x, _mm256_sub_ps(p11, p10)));
                let v = _mm256_add_ps(top, _mm256_mul_ps(y, _mm256_sub_ps(bot, top)));
                _mm256_storeu_ps(out[c].as_mut_ptr().add(k), _mm256_mul_ps(v, sc));
            }
            k += 8;
        }
        n
    }
}

/// Sums of 2x2 bytes of rows `a` and `b` into `d`, 16 at a time; returns how many were done.
///
/// # Safety
/// AVX2 must be available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sum4_row_avx2(a: &[u8], b: &[u8], d: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = (d.len().min(a.len() / 2).min(b.len() / 2)) / 16 * 16;
    // SAFETY (whole body): i + 16 <= n outputs, so 2 i + 32 <= 2 n input bytes of each row.
    unsafe {
        let ones = _mm256_set1_epi8(1);
        let mut i = 0;
        while i < n {
            let va = _mm256_loadu_si256(a.as_ptr().add(2 * i) as *const __m256i);
            let vb = _mm256_loadu_si256(b.as_ptr().add(2 * i) as *const __m256i);
            // Pairs of unsigned bytes times 1, summed: 16 words per row, exact.
            let s = _mm256_add_epi16(_mm256_maddubs_epi16(va, ones), _mm256_maddubs_epi16(vb, ones));
            _mm256_storeu_si256(d.as_mut_ptr().add(i) as *mut __m256i, s);
            i += 16;
        }
        n
    }
}

/// Shuffle masks: byte j of channel c's 16 bytes comes from byte 3 j + c of 48 interleaved
/// bytes, which lies in 16-byte block (3 j + c) / 16 (-1: none, the shuffle writes 0).
const RGB_SPLIT: [[[i8; 16]; 3]; 3] = {
    let mut idx = [[[-1i8; 16]; 3]; 3];
    let mut c = 0;
    while c < 3 {
        let mut j = 0;
        while j < 16 {
            let k = 3 * j + c;
            idx[c][k / 16][j] = (k % 16) as i8;
            j += 1;
        }
        c += 1;
    }
    idx
};

/// Channel `c` of the 16 pixels at `p` (48 bytes).
///
/// # Safety
/// SSSE3 must be available and 48 bytes readable at `p`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
#[inline]
unsafe fn split_channel(p: *const u8, m: &[std::arch::x86_64::__m128i; 3]) -> std::arch::x86_64::__m128i {
    use std::arch::x86_64::*;
    // SAFETY: the caller guarantees the feature and the 48 bytes.
    unsafe {
        let (x, y, z) = (
            _mm_loadu_si128(p as *const __m128i),
            _mm_loadu_si128(p.add(16) as *const __m128i),
            _mm_loadu_si128(p.add(32) as *const __m128i),
        );
        _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(x, m[0]), _mm_shuffle_epi8(y, m[1])), _mm_shuffle_epi8(z, m[2]))
    }
}

/// [`deinterleave`] 16 pixels per step; returns how many were done.
///
/// # Safety
/// SSSE3 must be available; `rgb` holds 3 bytes per element of `r`, `g`, `b`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
unsafe fn deinterleave_ssse3(rgb: &[u8], r: &mut [u8], g: &mut [u8], b: &mut [u8]) -> usize {
    use std::arch::x86_64::*;
    let n = r.len().min(g.len()).min(b.len()).min(rgb.len() / 3) / 16 * 16;
    // SAFETY (whole body): 3 (i + 16) <= 3 n bytes read, i + 16 <= n written per channel.
    unsafe {
        let m: [[__m128i; 3]; 3] = RGB_SPLIT.map(|per| per.map(|v| _mm_loadu_si128(v.as_ptr() as *const __m128i)));
        let mut i = 0;
        while i < n {
            let p = rgb.as_ptr().add(3 * i);
            for (c, dst) in [r.as_mut_ptr(), g.as_mut_ptr(), b.as_mut_ptr()].into_iter().enumerate() {
                _mm_storeu_si128(dst.add(i) as *mut __m128i, split_channel(p, &m[c]));
            }
            i += 16;
        }
        n
    }
}

/// Level-1 sums of the three channels: `r[i]` is the sum of the red bytes of pixels 2i and
/// 2i + 1 of rows `a` and `b` (interleaved RGB), and so on; SSSE3 where the CPU has it.
fn sum4_rgb_row(a: &[u8], b: &[u8], r: &mut [u16], g: &mut [u16], bl: &mut [u16]) {
    let n = r.len().min(g.len()).min(bl.len()).min(a.len() / 6).min(b.len() / 6);
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 detected; the kernel stays inside the slices.
        done = unsafe { sum4_rgb_row_avx2(&a[..6 * n], &b[..6 * n], &mut r[..n], &mut g[..n], &mut bl[..n]) };
    } else if is_x86_feature_detected!("ssse3") {
        // SAFETY: SSSE3 detected; the kernel stays inside the slices.
        done = unsafe { sum4_rgb_row_ssse3(&a[..6 * n], &b[..6 * n], &mut r[..n], &mut g[..n], &mut bl[..n]) };
    }
    for i in done..n {
        let s =
            |c: usize| a[6 * i + c] as u16 + a[6 * i + 3 + c] as u16 + b[6 * i + c] as u16 + b[6 * i + 3 + c] as u16;
        (r[i], g[i], bl[i]) = (s(0), s(1), s(2));
    }
}

/// [`sum4_rgb_row`] 8 texels (16 pixels, 48 bytes of each row) per step: each channel's 16
/// bytes are gathered with three byte shuffles, then `maddubs` adds the pixel pairs.
/// Returns how many texels were done.
///
/// # Safety
/// SSSE3 must be available; `a` and `b` hold at least 6 bytes per texel of `r`, `g`, `bl`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
unsafe fn sum4_rgb_row_ssse3(a: &[u8], b: &[u8], r: &mut [u16], g: &mut [u16], bl: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = r.len().min(g.len()).min(bl.len()).min(a.len() / 6).min(b.len() / 6) / 8 * 8;
    // SAFETY (whole body): 6 (i + 8) <= 6 n bytes are read from each row, i + 8 <= n
    // texels written to each channel.
    unsafe {
        let m: [[__m128i; 3]; 3] = RGB_SPLIT.map(|per| per.map(|v| _mm_loadu_si128(v.as_ptr() as *const __m128i)));
        let ones = _mm_set1_epi8(1);
        let mut i = 0;
        while i < n {
            let (pa, pb) = (a.as_ptr().add(6 * i), b.as_ptr().add(6 * i));
            for (c, dst) in [r.as_mut_ptr(), g.as_mut_ptr(), bl.as_mut_ptr()].into_iter().enumerate() {
                let s = _mm_add_epi16(
                    _mm_maddubs_epi16(split_channel(pa, &m[c]), ones),
                    _mm_maddubs_epi16(split_channel(pb, &m[c]), ones),
                );
                _mm_storeu_si128(dst.add(i) as *mut __m128i, s);
            }
            i += 8;
        }
        n
    }
}

/// [`sum4_rgb_row`] 16 texels (32 pixels) per step: the low lane takes pixels 0-15, the high
/// lane 16-31, each 48-byte block is loaded once for the three channels. Returns how many
/// texels were done.
///
/// # Safety
/// AVX2 must be available; `a` and `b` hold at least 6 bytes per texel of `r`, `g`, `bl`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sum4_rgb_row_avx2(a: &[u8], b: &[u8], r: &mut [u16], g: &mut [u16], bl: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = r.len().min(g.len()).min(bl.len()).min(a.len() / 6).min(b.len() / 6) / 16 * 16;
    // SAFETY (whole body): 6 (i + 16) <= 6 n bytes are read from each row, i + 16 <= n
    // texels written to each channel.
    unsafe {
        let m: [[__m256i; 3]; 3] = RGB_SPLIT
            .map(|per| per.map(|v| _mm256_broadcastsi128_si256(_mm_loadu_si128(v.as_ptr() as *const __m128i))));
        let ones = _mm256_set1_epi8(1);
        // Blocks k = 0, 1, 2 of pixels 0-15 (low lane) and 16-31 (high lane).
        let blocks = |p: *const u8| -> [__m256i; 3] {
            std::array::from_fn(|k| {
                let lo = _mm_loadu_si128(p.add(16 * k) as *const __m128i);
                let hi = _mm_loadu_si128(p.add(48 + 16 * k) as *const __m128i);
                _mm256_inserti128_si256::<1>(_mm256_castsi128_si256(lo), hi)
            })
        };
        let channel = |v: &[__m256i; 3], m: &[__m256i; 3]| {
            _mm256_or_si256(
                _mm256_or_si256(_mm256_shuffle_epi8(v[0], m[0]), _mm256_shuffle_epi8(v[1], m[1])),
                _mm256_shuffle_epi8(v[2], m[2]),
            )
        };
        let mut i = 0;
        while i < n {
            let (va, vb) = (blocks(a.as_ptr().add(6 * i)), blocks(b.as_ptr().add(6 * i)));
            for (c, dst) in [r.as_mut_ptr(), g.as_mut_ptr(), bl.as_mut_ptr()].into_iter().enumerate() {
                let s = _mm256_add_epi16(
                    _mm256_maddubs_epi16(channel(&va, &m[c]), ones),
                    _mm256_maddubs_epi16(channel(&vb, &m[c]), ones),
                );
                _mm256_storeu_si256(dst.add(i) as *mut __m256i, s);
            }
            i += 16;
        }
        n
    }
}

/// Splits interleaved RGB bytes into three channel rows (SSSE3 where the CPU has it).
fn deinterleave(rgb: &[u8], r: &mut [u8], g: &mut [u8], b: &mut [u8]) {
    let n = r.len().min(g.len()).min(b.len()).min(rgb.len() / 3);
    let (rgb, r, g, b) = (&rgb[..3 * n], &mut r[..n], &mut g[..n], &mut b[..n]);
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("ssse3") {
        // SAFETY: SSSE3 detected; the kernel stays inside the slices.
        done = unsafe { deinterleave_ssse3(rgb, r, g, b) };
    }
    for i in done..n {
        r[i] = rgb[3 * i];
        g[i] = rgb[3 * i + 1];
        b[i] = rgb[3 * i + 2];
    }
}

/// Sums of 2x2 words of rows `a` and `b` into `d`, 16 at a time (the column sums below 2^15,
/// as signed words for `madd`); returns how many were done.
///
/// # Safety
/// AVX2 must be available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sum4_u16_row_avx2(a: &[u16], b: &[u16], d: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = (d.len().min(a.len() / 2).min(b.len() / 2)) / 16 * 16;
    // SAFETY (whole body): i + 16 <= n outputs, so 2 i + 32 <= 2 n input words per row.
    unsafe {
        let ones = _mm256_set1_epi16(1);
        let mut i = 0;
        while i < n {
            let (pa, pb) = (a.as_ptr().add(2 * i) as *const __m256i, b.as_ptr().add(2 * i) as *const __m256i);
            let v0 = _mm256_add_epi16(_mm256_loadu_si256(pa), _mm256_loadu_si256(pb));
            let v1 = _mm256_add_epi16(_mm256_loadu_si256(pa.add(1)), _mm256_loadu_si256(pb.add(1)));
            let (s0, s1) = (_mm256_madd_epi16(v0, ones), _mm256_madd_epi16(v1, ones));
            // packus works per 128-bit lane: put the quarters back in order.
            let packed = _mm256_permute4x64_epi64::<0b11_01_10_00>(_mm256_packus_epi32(s0, s1));
            _mm256_storeu_si256(d.as_mut_ptr().add(i) as *mut __m256i, packed);
            i += 16;
        }
        n
    }
}

/// What the u16 box-sum pyramid is summed from: u8 pixels or u16 sums of 4^(l-1) pixels
/// (l <= 4, so every column sum stays below 2^15 until the last pair).
trait SumTexel: Copy + Into<u16> {
    /// A kernel for the leading texels of a row (it returns how many it did), when the CPU
    /// has what it needs.
    fn row_kernel() -> Option<RowKernel<Self>>;
}

/// Sums of 2x2 elements of rows `a` and `b` into `d`; returns how many were done.
type RowKernel<T> = unsafe fn(&[T], &[T], &mut [u16]) -> usize;

impl SumTexel for u8 {
    fn row_kernel() -> Option<RowKernel<u8>> {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            return Some(sum4_row_avx2 as RowKernel<u8>);
        }
        None
    }
}

impl SumTexel for u16 {
    fn row_kernel() -> Option<RowKernel<u16>> {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            return Some(sum4_u16_row_avx2 as RowKernel<u16>);
        }
        None
    }
}

/// One level of the u16 box-sum pyramid: texels `rect` of `dst` (rows of `lw`) are the sums
/// of 2x2 elements of `src` (rows of `sw`); 16 texels per step with AVX2 where the CPU has it.
fn sum4<T: SumTexel>(src: &[T], sw: usize, dst: &mut [u16], lw: usize, rect: [usize; 4]) {
    let [x0, y0, x1, y1] = rect;
    let n = x1 - x0;
    let kernel = T::row_kernel();
    for y in y0..y1 {
        let a = &src[2 * y * sw + 2 * x0..][..2 * n];
        let b = &src[(2 * y + 1) * sw + 2 * x0..][..2 * n];
        let d = &mut dst[y * lw + x0..y * lw + x1];
        // SAFETY: a kernel is only given when the CPU has its features; it stays inside the
        // three slices.
        let done = kernel.map_or(0, |k| unsafe { k(a, b, d) });
        for i in done..n {
            d[i] = a[2 * i].into() + a[2 * i + 1].into() + b[2 * i].into() + b[2 * i + 1].into();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
        /// Any parameters: a clear error or a map whose outputs are finite and within the
        /// input's range (fields are weighted means), for both field kinds.
        #[test]
        fn any_parameters_give_an_error_or_bounded_means(
            w in 1usize..40, h in 1usize..40, rings in 0usize..20, sectors in 0usize..20, fovea_rings in 0usize..4,
            rho0 in -2.0f64..10.0, rho_max in -1.0f64..40.0, cx in -20.0f64..60.0, cy in -20.0f64..60.0,
            max_level in 0usize..6, area in any::<bool>(), seed in any::<u64>(),
        ) {
            let cfg = LogPolarConfig {
                rings, sectors, fovea_rings, fovea_radius: rho0, max_radius: rho_max, centre: [cx, cy], max_level,
                min_field_texels: 1.0, fields: if area { Fields::Area } else { Fields::Pyramid },
            };
            if let Ok(map) = LogPolarMap::new(&cfg, w, h) {
                let mut rng = ocellus_image::rng::SplitMix64::new(seed);
                let img = Plane::from_fn(w, h, |_, _| 50 + rng.below(100) as u8);
                let out = map.sample_grey(&img).unwrap();
                prop_assert_eq!(out.size(), (sectors, map.rows()));
                for (v, cov) in out.rows().flatten().zip(map.coverage()) {
                    prop_assert!(v.is_finite());
                    // Cells that read the image see only values in 50..150.
                    if *cov > 0.0 {
                        prop_assert!((49.99..=150.01).contains(v), "{} (coverage {})", v, cov);
                    }
                }
                let inv = map.inverse(&out).unwrap();
                prop_assert!(inv.all_finite());
            }
        }
    }

    #[test]
    fn the_grey_fast_path_equals_the_general_one() {
        // Gaze points in the middle, near a corner (cells off the image, quads at the last
        // row and column) and outside the image.
        let (w, h) = (203, 157);
        let mut rng = ocellus_image::rng::SplitMix64::new(5);
        let img = Plane::from_fn(w, h, |_, _| rng.below(256) as u8);
        let f = img.map(|v| v as f32);
        for centre in [[101.0, 78.0], [199.5, 154.2], [3.0, 150.0], [-30.0, 40.0]] {
            let cfg = LogPolarConfig { centre, rings: 40, sectors: 37, ..LogPolarConfig::for_image(w, h) };
            let map = LogPolarMap::new(&cfg, w, h).unwrap();
            assert!(map.level_ranges.is_some());
            let (fast, general) = (map.sample_grey(&img).unwrap(), map.sample_f32(&f).unwrap());
            for (a, b) in fast.rows().flatten().zip(general.rows().flatten()) {
                assert!((a - b).abs() < 1e-3, "{centre:?}: {a} {b}");
            }
        }
    }

    #[test]
    fn the_rgb_fast_path_equals_the_general_one_per_channel() {
        let (w, h) = (190, 141);
        let mut rng = ocellus_image::rng::SplitMix64::new(8);
        let img = Plane::from_fn(w, h, |_, _| [rng.below(256) as u8, rng.below(256) as u8, rng.below(256) as u8]);
        for centre in [[95.0, 70.0], [187.0, 2.5], [-10.0, 60.0]] {
            let cfg = LogPolarConfig { centre, rings: 33, sectors: 41, ..LogPolarConfig::for_image(w, h) };
            let map = LogPolarMap::new(&cfg, w, h).unwrap();
            let fast = map.sample_rgb(&img).unwrap();
            // Area fields go through the general interleaved path.
            let area = LogPolarMap::new(&LogPolarConfig { fields: Fields::Area, ..cfg }, w, h).unwrap();
            let area_rgb = area.sample_rgb(&img).unwrap();
            for c in 0..3 {
                let chan = img.map(|p| p[c] as f32);
                let general = map.sample_f32(&chan).unwrap();
                for (a, b) in fast[c].rows().flatten().zip(general.rows().flatten()) {
                    assert!((a - b).abs() < 1e-3, "{centre:?} channel {c}: {a} {b}");
                }
                let area_general = area.sample_f32(&chan).unwrap();
                for (a, b) in area_rgb[c].rows().flatten().zip(area_general.rows().flatten()) {
                    assert!((a - b).abs() < 1e-3, "{centre:?} area channel {c}: {a} {b}");
                }
            }
        }
    }

    #[test]
    fn huge_or_degenerate_maps_are_refused_with_a_reason() {
        let base = LogPolarConfig::for_image(64, 64);
        for (cfg, why) in [
            (LogPolarConfig { rings: 60_000, sectors: 60_000, ..base }, "cells"),
            (LogPolarConfig { max_radius: 1.0, ..base }, "outer radius"),
            (LogPolarConfig { centre: [f64::NAN, 3.0], ..base }, "gaze"),
            (LogPolarConfig { max_level: 5, ..base }, "level"),
        ] {
            let e = LogPolarMap::new(&cfg, 64, 64).unwrap_err().to_string();
            assert!(e.contains(why), "{e}");
        }
        assert!(LogPolarMap::new(&base, 0, 64).is_err());
    }

    #[test]
    fn a_shifted_map_equals_one_built_at_the_new_gaze_point() {
        let (w, h) = (120, 90);
        let img = Plane::from_fn(w, h, |x, y| ((x * 13 + y * 7 + x * y / 5) % 251) as u8);
        let cfg = LogPolarConfig {
            rings: 10,
            sectors: 24,
            fovea_rings: 2,
            fovea_radius: 2.0,
            max_radius: 20.0,
            centre: [60.0, 45.0],
            max_level: 0,
            min_field_texels: 1.0,
            fields: Fields::Area,
        };
        let map = LogPolarMap::new(&cfg, w, h).unwrap();
        let moved = map.shifted(-17, 9).unwrap();
        let fresh = LogPolarMap::new(&LogPolarConfig { centre: [43.0, 54.0], ..cfg }, w, h).unwrap();
        let (a, b) = (moved.sample_grey(&img).unwrap(), fresh.sample_grey(&img).unwrap());
        for (x, y) in a.rows().flatten().zip(b.rows().flatten()) {
            assert!((x - y).abs() < 1e-3, "{x} {y}");
        }
        // Not when the fields would leave the image, nor for pyramid maps.
        assert!(map.shifted(-50, 0).is_none());
        let pyr = LogPolarMap::new(&LogPolarConfig { max_level: 3, fields: Fields::Pyramid, ..cfg }, w, h).unwrap();
        assert!(pyr.shifted(1, 0).is_none());
    }

    #[test]
    fn a_quarter_turn_is_a_shift_by_a_quarter_of_the_sectors() {
        // 32 = 2^5: the pyramid's texel grids are symmetric about the centre (15.5, 15.5) at
        // every level, so pyramid fields turn with the image too (for other sizes they do up
        // to the grid, as the 512x512 test on a real image shows).
        let n = 32;
        let img = Plane::from_fn(n, n, |x, y| ((x * 37 + y * 11 + x * y) % 200) as u8);
        let quarter = Plane::from_fn(n, n, |x, y| img.get(y, n - 1 - x));
        for fields in [Fields::Pyramid, Fields::Area] {
            let cfg = LogPolarConfig { rings: 12, sectors: 16, fields, ..LogPolarConfig::for_image(n, n) };
            let map = LogPolarMap::new(&cfg, n, n).unwrap();
            let (a, b) = (map.sample_grey(&img).unwrap(), map.sample_grey(&quarter).unwrap());
            for y in 0..map.rows() {
                for x in 0..16 {
                    assert!((b.get((x + 4) % 16, y) - a.get(x, y)).abs() < 1e-2, "{fields:?} row {y} sector {x}");
                }
            }
        }
    }
}
