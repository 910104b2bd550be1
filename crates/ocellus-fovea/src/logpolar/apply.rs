//! Applying a map to a frame: the general table (any source, interleaved channels) and the
//! fast paths of [`Fields::Pyramid`] for grey and RGB bytes (u16 box-sum pyramid, quads
//! level by level).

use super::box_pyramid::{deinterleave, halve, sum4, sum4_rgb_row, Texel};
use super::quads::quads;
use super::{level_size, Fields, LogPolarMap, Scratch};

impl LogPolarMap {
    /// Builds the box pyramid (means of 2^l x 2^l pixels) of `src` (C interleaved channels)
    /// up to the coarsest level a field reads, then applies the table. Full-resolution reads
    /// are moved by `moved` pixels (a gaze point moved by whole pixels, see
    /// [`LogPolarMap::sample_grey_moved_into`]; 0 otherwise).
    pub(super) fn apply<T: Texel, const C: usize>(
        &self,
        src: &[T],
        moved: isize,
        scratch: &mut Scratch,
        out: &mut [f32],
    ) {
        let top = self.levels;
        if top > 0 {
            scratch.pyramid.resize(self.pyramid_len() * C, 0.0);
            for l in 1..=top {
                let Some(rect) = self.level_rect(l) else { continue };
                let (pw, _) = level_size(self.width, self.height, l - 1);
                let (lw, lh) = level_size(self.width, self.height, l);
                let (lo, hi) = scratch.pyramid.split_at_mut(self.level_base[l] * C);
                let dst = &mut hi[..lw * lh * C];
                if l == 1 {
                    halve::<T, C>(src, pw, dst, lw, rect, &mut scratch.row);
                } else {
                    let prev = &lo[self.level_base[l - 1] * C..];
                    halve::<f32, C>(prev, pw, dst, lw, rect, &mut scratch.row);
                }
            }
        }
        let pyr = &scratch.pyramid;
        if self.cfg.fields == Fields::Pyramid {
            self.apply_quads::<T, C>(src, moved, pyr, out);
            return;
        }
        for (c, o) in out.chunks_exact_mut(C).enumerate() {
            let (s, e) = (self.start[c] as usize, self.start[c + 1] as usize);
            let (offs, ws) = (&self.offset[s..e], &self.weight[s..e]);
            let mut acc = [0.0f32; C];
            if self.level[c] == 0 {
                for (&i, &w) in offs.iter().zip(ws) {
                    let i = (i as isize + moved) as usize * C;
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
    fn apply_quads<T: Texel, const C: usize>(&self, src: &[T], moved: isize, pyr: &[f32], out: &mut [f32]) {
        let row_step: Vec<usize> = (0..=self.levels).map(|l| level_size(self.width, self.height, l).0 * C).collect();
        for ((((o, &b), &fx), &fy), &l) in
            out.chunks_exact_mut(C).zip(&self.quad_base).zip(&self.quad_fx).zip(&self.quad_fy).zip(&self.level)
        {
            let b = if l == 0 { (b as isize + moved) as usize } else { b as usize };
            let (i, dy) = (b * C, row_step.get(l as usize).copied().unwrap_or(0));
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
    /// as one run of bilinear quads, 8 cells per step with AVX2 gathers for a resolved
    /// `Avx2` backend. Returns false (nothing done) when the map does not allow it.
    pub(super) fn apply_grey_pyramid(&self, src: &[u8], scratch: &mut Scratch, out: &mut [f32]) -> bool {
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
        let backend = self.cfg.backend.resolve();
        for l in 1..=self.levels {
            let Some(rect) = self.level_rect(l) else { continue };
            let (pw, _) = level_size(w, h, l - 1);
            let (lw, lh) = level_size(w, h, l);
            let (lo, hi) = pyr.split_at_mut(self.level_base[l]);
            let dst = &mut hi[..lw * lh];
            if l == 1 {
                if let Some(src) = level0 {
                    sum4(backend, src, pw, dst, lw, rect);
                }
            } else {
                sum4(backend, &lo[self.level_base[l - 1]..], pw, dst, lw, rect);
            }
        }
    }

    /// Every cell's quad, level by level; sums at level l are scaled by 4^-l.
    fn grey_quads<const K: usize>(&self, level0: [&[u8]; K], pyr: [&[u16]; K], mut out: [&mut [f32]; K]) {
        let Some(ranges) = &self.level_ranges else { return };
        let backend = self.cfg.backend.resolve();
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
                quads(backend, level0, lw, b, fx, fy, 1.0, o);
            } else {
                quads(backend, pyr, lw, b, fx, fy, scale, o);
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
    pub(super) fn apply_rgb_pyramid(&self, flat: &[u8], scratch: &mut Scratch, out: &mut [&mut [f32]; 3]) -> bool {
        let (w, h) = (self.width, self.height);
        let (n, cells) = (w * h, self.quad_base.len());
        if self.level_ranges.is_none() || flat.len() < 3 * n || out.iter().any(|o| o.len() < cells) {
            return false;
        }
        // Planes `n + 320` bytes apart: whole multiples of 4 KiB (640x480 is 75 x 4 KiB) make
        // the three stores per pixel alias.
        let pitch = n + 320;
        let backend = self.cfg.backend.resolve();
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
                    backend,
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
                sum4_rgb_row(backend, a, b, &mut pr[span.clone()], &mut pg[span.clone()], &mut pb[span]);
            }
        }
        for p in pyr.chunks_exact_mut(plen.max(1)).take(3) {
            self.grey_levels(None, p);
        }
        let [o0, o1, o2] = out;
        let level0 = [&planes[..n], &planes[pitch..pitch + n], &planes[2 * pitch..2 * pitch + n]];
        let p = [&pyr[..plen], &pyr[plen..2 * plen], &pyr[2 * plen..3 * plen]];
        self.grey_quads(level0, p, [&mut o0[..cells], &mut o1[..cells], &mut o2[..cells]]);
        scratch.planes = planes;
        scratch.pyramid_rgb = pyr;
        true
    }
}
