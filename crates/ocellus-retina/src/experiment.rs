//! The seed's two experiments (SPEC 8.3) and reduced versions of them.
//!
//! 1. **Sensor design**: 60 fixed motor fields in a 2D motor space (M = identity, q
//!    one-hot), 68 triplets per field (4080), 2877 pixels, 48 receptive fields: S 138,096 +
//!    P 138,240 = 276,336 variables (the seed: "about 275,000"). The fields tile the motor
//!    space as 10 x 6 cells and each triplet's action lies anywhere in its field's cell
//!    ([`MotorSpace::Cells`], the default), or each field is one exact action value
//!    ([`MotorSpace::Values`]). With cells, one predictor serves a range of actions, and
//!    the spread of what it must predict grows with eccentricity under rotation and
//!    dilation but not under translation: the pressure that makes peripheral fields large.
//! 2. **Co-development**: a 15 x 15 grid of motor cells over the 2D motor space (225), 481
//!    pixels, 16 receptive fields and 16 motor fields, all learned; 22,500 triplets with
//!    uniform random actions: S 7,696 + M 3,600 + P 4,096 = 15,392 (the seed: "about
//!    15,000").
//!
//! Held-out triplets come from the same images at other gaze points (another seed), so the
//! held-out error measures the prediction, not the memory of patches.

use crate::action::{Action, ActionKinds, ActionRanges, MotorCode};
use crate::disc::Disc;
use crate::experience::{render, Experience};
use crate::model::{fit_scale, Free, Params, Shape};
use crate::{Real, Result, RetinaError};
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;

/// Which experiment, and its sizes.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExperimentConfig {
    /// 1 (sensor design: fixed motor fields) or 2 (co-development: motor fields learned).
    pub experiment: u8,
    /// Pixels of the disc.
    pub pixels: usize,
    /// Receptive fields.
    pub fields: usize,
    /// Experiment 1: action values (= fixed motor fields); experiment 2: motor fields.
    pub motor_fields: usize,
    /// Experiment 2: motor cells per axis of the grid (225 = 15 x 15).
    pub grid_cells: usize,
    /// Experiment 1: triplets per action value; experiment 2: triplets in all.
    pub triplets: usize,
    /// Held-out triplets (experiment 1: per action value).
    pub heldout: usize,
    /// The actions.
    pub actions: ActionKinds,
    /// Weight of the simplicity term.
    pub simplicity: f64,
    /// Seed of the experience (gaze points, images, random actions) and of the start.
    pub seed: u64,
    /// Gaussian blur of the source images before sampling (the eye's optics), sigma in
    /// pixels; 0 for none.
    pub blur_px: f64,
    /// Factor on the default largest actions of [`ActionRanges::for_radius`] (shift r / 2,
    /// rotation 30 degrees, log-scale 0.3): [`ExperimentConfig::sensor_design`] sets
    /// [`sensor_design_action_scale`] (5 for rotation + dilation, 1.5 for translation, 1 for
    /// all four actions), experiment 2 sets 1. A config
    /// switched to [`MotorSpace::Values`] keeps what it had; the CLI then sets 1, the ranges the
    /// values were first built with.
    pub action_scale: f64,
    /// Experiment 2: weight of the motor fields' smoothness over the motor grid (see
    /// [`crate::model::Objective::smoothness`]); 0 for none.
    pub motor_smoothness: f64,
    /// Experiment 1: what a fixed motor field stands for (checkpoints written before this
    /// choice existed were of [`MotorSpace::Values`]).
    #[serde(default = "MotorSpace::values")]
    pub motor_space: MotorSpace,
}

/// Experiment 1: what each of its fixed motor fields stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotorSpace {
    /// A cell of a grid tiling the 2D motor space (see [`ActionRanges::cells`]); each
    /// triplet's action is drawn uniformly inside its field's cell. Translation or
    /// rotation + dilation only.
    Cells,
    /// One exact action value, spread evenly over the axes (see
    /// [`ActionRanges::discrete`]); all four actions allowed.
    Values,
}

impl MotorSpace {
    fn values() -> Self {
        Self::Values
    }

    /// Name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cells => "cells",
            Self::Values => "values",
        }
    }
}

impl ExperimentConfig {
    /// The seed's experiment 1 at its size.
    pub fn sensor_design(actions: ActionKinds) -> Self {
        Self {
            experiment: 1,
            pixels: 2877,
            fields: 48,
            motor_fields: 60,
            grid_cells: 0,
            triplets: 68,
            heldout: 17,
            actions,
            simplicity: DEFAULT_SIMPLICITY,
            seed: 1,
            blur_px: DEFAULT_BLUR_PX,
            action_scale: sensor_design_action_scale(actions),
            motor_smoothness: 0.0,
            motor_space: if actions == ActionKinds::All { MotorSpace::Values } else { MotorSpace::Cells },
        }
    }

    /// The seed's experiment 2 at its size.
    pub fn co_development(actions: ActionKinds) -> Self {
        Self {
            experiment: 2,
            pixels: 481,
            fields: 16,
            motor_fields: 16,
            grid_cells: 15,
            triplets: 22_500,
            heldout: 2_500,
            action_scale: 1.0,
            ..Self::sensor_design(actions)
        }
    }

    /// Experiment 1 reduced for tests: 481 pixels, 16 fields, 20 motor fields x 24
    /// triplets.
    pub fn sensor_design_small(actions: ActionKinds) -> Self {
        Self { pixels: 481, fields: 16, motor_fields: 20, triplets: 24, heldout: 8, ..Self::sensor_design(actions) }
    }

    /// Checks the sizes and the weight.
    pub fn validate(&self) -> Result<()> {
        if !matches!(self.experiment, 1 | 2) {
            return Err(RetinaError::Invalid(format!("experiment {}: there are experiments 1 and 2", self.experiment)));
        }
        if self.experiment == 2 && self.actions == ActionKinds::All {
            return Err(RetinaError::Invalid(
                "experiment 2 has a 2D motor space: use translation or rotation-dilation actions".into(),
            ));
        }
        if self.experiment == 1 && self.motor_space == MotorSpace::Cells && self.actions == ActionKinds::All {
            return Err(RetinaError::Invalid(
                "motor fields as cells tile a 2D motor space: use translation or rotation-dilation actions, or motor fields as values"
                    .into(),
            ));
        }
        if self.experiment == 2 && self.grid_cells < 2 {
            return Err(RetinaError::Invalid(format!(
                "a motor grid needs at least 2 cells per axis, not {}",
                self.grid_cells
            )));
        }
        if self.triplets == 0 || self.heldout == 0 {
            return Err(RetinaError::Invalid("an experiment needs training and held-out triplets".into()));
        }
        if !(self.simplicity.is_finite() && self.simplicity >= 0.0) {
            return Err(RetinaError::Invalid(format!("simplicity weight {} must be finite and >= 0", self.simplicity)));
        }
        if !(self.action_scale.is_finite() && self.action_scale > 0.0 && self.action_scale <= 5.0) {
            return Err(RetinaError::Invalid(format!("action scale {} must lie in (0, 5]", self.action_scale)));
        }
        if !(self.motor_smoothness.is_finite() && self.motor_smoothness >= 0.0) {
            return Err(RetinaError::Invalid(format!(
                "motor smoothness {} must be finite and >= 0",
                self.motor_smoothness
            )));
        }
        if !(self.blur_px.is_finite() && (0.0..=50.0).contains(&self.blur_px)) {
            return Err(RetinaError::Invalid(format!("blur sigma {} px must lie in [0, 50]", self.blur_px)));
        }
        self.shape().validate()
    }

    /// The model's sizes.
    pub fn shape(&self) -> Shape {
        let motor_cells = if self.experiment == 1 { self.motor_fields } else { self.grid_cells * self.grid_cells };
        Shape { pixels: self.pixels, fields: self.fields, motor_fields: self.motor_fields, motor_cells }
    }

    /// Which blocks are learned.
    pub fn free(&self) -> Free {
        Free { s: true, m: self.experiment == 2, p: true }
    }

    /// The smoothness term of the objective (experiment 2 with a positive weight).
    pub fn smoothness(&self) -> Option<crate::model::MotorSmoothness> {
        (self.experiment == 2 && self.motor_smoothness > 0.0)
            .then_some(crate::model::MotorSmoothness { cells: self.grid_cells, weight: self.motor_smoothness })
    }

    /// The number of learned variables.
    pub fn variables(&self) -> usize {
        let [s, m, p] = self.shape().sizes();
        s + p + if self.experiment == 2 { m } else { 0 }
    }
}

/// Default weight lambda of the simplicity term.
pub const DEFAULT_SIMPLICITY: f64 = 1e-3;

/// Experiment 1's factor on the largest rotations and dilations of
/// [`ActionRanges::for_radius`] with its motor fields as cells: rotations up to 150 degrees
/// (nearly the whole circle), dilations up to e^1.5, so that each of the 10 x 6 cells spans 30
/// degrees and 0.5 in log-scale. A cell's predictor serves its whole range: under rotation and
/// dilation the content of a pixel at eccentricity e lands anywhere along an arc of about
/// 0.5 e, which at the rim (15 px) exceeds the width of a field of the uniform tiling (about 9
/// px across), so fine fields pay only near the centre. Seed 1, PGD, interior fields' fovea
/// index and density ratio centre / periphery at factors 1 / 2 / 3 / 5: 0.23 / 0.31 / 0.43 /
/// 0.73 and 1.0 / 1.0 / 1.36 / 1.65 (`ocellus retina learn --experiment 1 --actions
/// rotation-dilation --action-scale K`). With exact action values (and all four actions)
/// the factor is 1.
pub const SENSOR_DESIGN_ACTION_SCALE: f64 = 5.0;

/// Experiment 1's factor on the largest shifts with its motor fields as cells: shifts up to
/// 0.75 disc radii on each axis. Chosen so that translations keep as much of the view as
/// rotations and dilations at [`SENSOR_DESIGN_ACTION_SCALE`]: on average 64 % of what the disc
/// shows after a shift it showed before, against 66 % (a rotation keeps all, a zoom out by e^s
/// keeps e^2s; [`ActionRanges::mean_kept_share`]). The two action sets then ask to predict as
/// much and differ only in how content moves. At factor 5 (shifts to 2.5 radii) a shift keeps
/// 13 % on average and half of them show nothing seen before: seeds 1-3, the learned model beat
/// the random-S baseline by only 1.07-1.11x (1.70-1.71x at 1.5), and the central fields grew
/// to 80-93 px^2 against 71-74 in the periphery (at 1.5: 54-59 against 55-58).
pub const SENSOR_DESIGN_SHIFT_SCALE: f64 = 1.5;

/// Experiment 1's default factor on the largest actions of `actions` with its motor fields as
/// cells ([`SENSOR_DESIGN_ACTION_SCALE`] or [`SENSOR_DESIGN_SHIFT_SCALE`]; 1 for all four
/// actions, which take exact values).
pub fn sensor_design_action_scale(actions: ActionKinds) -> f64 {
    match actions {
        ActionKinds::Translation => SENSOR_DESIGN_SHIFT_SCALE,
        ActionKinds::RotationDilation => SENSOR_DESIGN_ACTION_SCALE,
        ActionKinds::All => 1.0,
    }
}

/// Default blur of the sources, pixels (none).
pub const DEFAULT_BLUR_PX: f64 = 0.0;

/// An experiment ready to learn: the disc, the motor code and the experiences.
#[derive(Clone, Debug)]
pub struct Setup<T> {
    /// The settings.
    pub config: ExperimentConfig,
    /// The sensor.
    pub disc: Disc,
    /// The action ranges.
    pub ranges: ActionRanges,
    /// The motor code.
    pub code: MotorCode,
    /// Training triplets.
    pub train: Experience<T>,
    /// Held-out triplets.
    pub heldout: Experience<T>,
}

/// Builds the experiences from grey source images ([0, 1]).
pub fn setup<T: Real>(config: &ExperimentConfig, sources: &[Plane<f32>]) -> Result<Setup<T>> {
    config.validate()?;
    let disc = Disc::with_pixels(config.pixels)?;
    let d = ActionRanges::for_radius(disc.radius());
    let k = config.action_scale;
    let ranges =
        ActionRanges { shift_px: k * d.shift_px, rotation_rad: k * d.rotation_rad, log_scale: k * d.log_scale };
    let (code, train_actions, held_actions) = if config.experiment == 1 && config.motor_space == MotorSpace::Cells {
        let cells = ranges.cells(config.actions, config.motor_fields)?;
        let extent = ranges.extent(config.actions)?;
        let mut rng = SplitMix64::new(config.seed ^ 0xCE11_5EED);
        let mut draw = |per: usize| -> Result<Vec<Action>> {
            let mut v = Vec::with_capacity(per * config.motor_fields);
            for cell in 0..config.motor_fields {
                for _ in 0..per {
                    v.push(ranges.in_cell(config.actions, cells, cell, [rng.unit(), rng.unit()])?);
                }
            }
            Ok(v)
        };
        let (a, b) = (draw(config.triplets)?, draw(config.heldout)?);
        (MotorCode::Cells { nx: cells.0, ny: cells.1, extent }, a, b)
    } else if config.experiment == 1 {
        let values = ranges.discrete(config.actions, config.motor_fields)?;
        let rep = |k: usize| values.iter().flat_map(|a| std::iter::repeat_n(*a, k)).collect::<Vec<Action>>();
        (MotorCode::OneHot(values.clone()), rep(config.triplets), rep(config.heldout))
    } else {
        let extent = ranges.extent(config.actions)?;
        let mut rng = SplitMix64::new(config.seed ^ 0xA5A5_5A5A);
        let mut draw = |n: usize| -> Result<Vec<Action>> {
            (0..n).map(|_| ranges.uniform(config.actions, [rng.unit(), rng.unit()])).collect()
        };
        let (a, b) = (draw(config.triplets)?, draw(config.heldout)?);
        (MotorCode::Grid { cells: config.grid_cells, extent }, a, b)
    };
    let blurred: Vec<Plane<f32>>;
    let sources = if config.blur_px > 0.0 {
        blurred = sources
            .iter()
            .map(|p| ocellus_image::filter::gaussian_blur(ocellus_image::Backend::Auto, p, config.blur_px as f32))
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| RetinaError::Invalid(format!("blurring the sources: {e}")))?;
        &blurred[..]
    } else {
        sources
    };
    let train = render(sources, &disc, &train_actions, &code, config.seed)?;
    let heldout = render(sources, &disc, &held_actions, &code, config.seed.wrapping_add(0x5EED_0F4E_1D00))?;
    Ok(Setup { config: *config, disc, ranges, code, train, heldout })
}

/// How the learning starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Init {
    /// Every entry uniform random (see [`Params::random`]): every field starts as a noisy
    /// average of the whole disc, and the fields must first break their symmetry.
    Uniform,
    /// Each receptive field starts as a Gaussian blob at a centre drawn uniformly over the
    /// disc's area, its width drawn uniformly from 0.5 to 1.5 times the width at which the
    /// fields would tile the disc, independently of the centre (so the start has no relation
    /// of size to eccentricity, no fovea, by construction), plus a floor of 1 % noise; each
    /// row sums to 1. The predictors start near "nothing changes" (P_k = I plus 10 % noise)
    /// and learned motor fields as bumps at random cells of the motor grid, width about the
    /// grid over the square root of their number, +-50 %. The default: it skips the slow
    /// symmetry breaking of `Uniform`.
    Blobs,
}

impl std::str::FromStr for Init {
    type Err = RetinaError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "uniform" => Ok(Self::Uniform),
            "blobs" => Ok(Self::Blobs),
            _ => Err(RetinaError::Invalid(format!("init '{s}': use blobs or uniform"))),
        }
    }
}

/// The seeded starting point, its predictors scaled to fit the data (see [`fit_scale`]).
pub fn start<T: Real>(setup: &Setup<T>, init: Init, seed: u64) -> Result<Params<T>> {
    let c = &setup.config;
    let shape = c.shape();
    let mut p = Params::random(shape, c.experiment == 1, seed)?;
    if init == Init::Blobs {
        let mut rng = SplitMix64::new(seed ^ 0xB10B);
        let (n, r) = (shape.pixels, shape.fields);
        let radius = setup.disc.radius().max(0.5);
        let tile = (n as f64 / (std::f64::consts::PI * r as f64)).sqrt();
        for i in 0..r {
            let (rho, phi) = (radius * rng.unit().sqrt(), std::f64::consts::TAU * rng.unit());
            let (cx, cy) = (rho * phi.cos(), rho * phi.sin());
            let w = tile * (0.5 + rng.unit());
            let row = &mut p.s[i * n..(i + 1) * n];
            let mut sum = 0.0;
            let vals: Vec<f64> = setup
                .disc
                .offsets()
                .iter()
                .map(|&[x, y]| {
                    let d2 = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2);
                    let v = (-d2 / (2.0 * w * w)).exp() + 0.01 * rng.unit();
                    sum += v;
                    v
                })
                .collect();
            for (o, v) in row.iter_mut().zip(vals) {
                *o = T::from_f64(v / sum);
            }
        }
        for k in 0..shape.motor_fields {
            for a in 0..r {
                for b in 0..r {
                    let v = if a == b { 1.0 } else { 0.0 } + 0.1 * rng.unit();
                    p.p[(k * r + a) * r + b] = T::from_f64(v);
                }
            }
        }
        if c.experiment == 2 {
            // Learned motor fields start as bumps too, at random cells of the motor grid:
            // from uniform or uniform random fields, every action mixes the same predictors,
            // their gradients agree, and the fields never specialize (tried: they stay noise,
            // or turn flat under a smoothness term).
            let n = c.grid_cells;
            let width = n as f64 / (shape.motor_fields as f64).sqrt();
            for k in 0..shape.motor_fields {
                let (cx, cy) = (rng.unit() * (n - 1) as f64, rng.unit() * (n - 1) as f64);
                let w = width * (0.5 + rng.unit());
                for y in 0..n {
                    for x in 0..n {
                        let d2 = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2);
                        let v = (-d2 / (2.0 * w * w)).exp() + 0.01 * rng.unit();
                        p.m[k * n * n + y * n + x] = T::from_f64(v);
                    }
                }
            }
        }
    }
    fit_scale(&setup.train, &mut p);
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_variable_counts_are_the_seeds() {
        let one = ExperimentConfig::sensor_design(ActionKinds::Translation);
        assert_eq!(one.shape().sizes()[0], 138_096);
        assert_eq!(one.shape().sizes()[2], 138_240);
        assert_eq!(one.variables(), 276_336);
        assert_eq!(one.motor_fields * one.triplets, 4080);
        let two = ExperimentConfig::co_development(ActionKinds::RotationDilation);
        assert_eq!(two.shape().sizes(), [7_696, 3_600, 4_096]);
        assert_eq!(two.variables(), 15_392);
        // Wide ranges where the motor fields are cells; the first build's where not.
        assert_eq!(one.action_scale, SENSOR_DESIGN_SHIFT_SCALE);
        assert_eq!(
            ExperimentConfig::sensor_design(ActionKinds::RotationDilation).action_scale,
            SENSOR_DESIGN_ACTION_SCALE
        );
        assert_eq!(two.action_scale, 1.0);
        assert_eq!(ExperimentConfig::sensor_design(ActionKinds::All).action_scale, 1.0);
        // The two action sets' default ranges keep about as much of the view (64 % and 66 %).
        let r = Disc::with_pixels(2877).unwrap().radius();
        let kept = |actions: ActionKinds| {
            let (d, k) = (ActionRanges::for_radius(r), ExperimentConfig::sensor_design(actions).action_scale);
            ActionRanges { shift_px: k * d.shift_px, rotation_rad: k * d.rotation_rad, log_scale: k * d.log_scale }
                .mean_kept_share(actions, r)
                .unwrap()
        };
        let (tr, rd) = (kept(ActionKinds::Translation), kept(ActionKinds::RotationDilation));
        assert!((tr - 0.642).abs() < 0.01 && (rd - 0.658).abs() < 0.01, "{tr} {rd}");
        assert!(ExperimentConfig { actions: ActionKinds::All, ..two }.validate().is_err());
        // All four actions have no 2D motor space to tile.
        assert_eq!(ExperimentConfig::sensor_design(ActionKinds::All).motor_space, MotorSpace::Values);
        assert!(ExperimentConfig { actions: ActionKinds::All, motor_space: MotorSpace::Cells, ..one }
            .validate()
            .is_err());
        assert!(ExperimentConfig { fields: 0, ..one }.validate().is_err());
        assert!(ExperimentConfig { simplicity: f64::NAN, ..one }.validate().is_err());
    }

    #[test]
    fn a_config_saved_before_motor_spaces_existed_reads_as_values() {
        let cells = ExperimentConfig::sensor_design(ActionKinds::RotationDilation);
        assert_eq!(cells.motor_space, MotorSpace::Cells);
        let mut json = serde_json::to_value(cells).unwrap();
        assert_eq!(json["motor_space"], "cells");
        json.as_object_mut().unwrap().remove("motor_space");
        let old: ExperimentConfig = serde_json::from_value(json).unwrap();
        assert_eq!(old, ExperimentConfig { motor_space: MotorSpace::Values, ..cells });
    }
}
