//! `ocellus plan corridor`: the view-planning experiment, with frames, a CSV and plots.

use crate::plot;
use anyhow::Result;
use clap::{Args, Subcommand};
use ocellus_image::Plane;
use ocellus_sim::corridor_experiment::{self as corridor_sim, CorridorImages, RunConfig, StepRecord};
use ocellus_synth::corridor::Corridor;
use plotters::style::RGBColor;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus plan`.
#[derive(Args, Debug)]
pub struct PlanArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Subcommand, Debug)]
enum What {
    /// The seed's corridor: a robot drives 0.5 m per step and points its camera by expected
    /// information gain (landmark bearings for self-localization, or surprise when the context
    /// is unfamiliar).
    Corridor(CorridorArgs),
}

#[derive(Args, Debug)]
struct CorridorArgs {
    /// A person appears suddenly at step 5 (the bottom-up case).
    #[arg(long)]
    event: bool,
    /// Number of planning steps. Range: 1..=10000.
    #[arg(long, default_value_t = 16, value_parser = crate::ranges::within(1usize, 10_000))]
    steps: usize,
    /// Seed of odometry, bearing and sensor noise. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder.
    #[arg(long, default_value = "ocellus-plan")]
    out: PathBuf,
}

/// Marks the landmarks (yellow rings at camera height) and the chosen direction (a vertical
/// line: green for a top-down choice, red for bottom-up) on the step's frame.
fn annotate(world: &Corridor, r: &StepRecord, frame: &ocellus_image::convert::RgbImage) -> Plane<[u8; 3]> {
    let mut img = frame.to_u8();
    let row = (img.height() as f32 - 1.0) / 2.0;
    for (lx, ly) in world.landmarks() {
        let b = (ly - r.true_xy.1).atan2(lx - r.true_xy.0).to_degrees();
        if let Some(u) = world.column_of(b, r.pan_deg) {
            ocellus_image::draw::ring(&mut img, u as f32, row, 18.0, [255, 230, 0]);
        }
    }
    let color = if r.decision.v >= 0.5 { [40, 230, 60] } else { [250, 40, 40] };
    if let Some(u) = world.column_of(r.decision.pan_deg, r.pan_deg) {
        let u = (u.round() as usize).min(img.width() - 1);
        for y in 0..img.height() {
            for x in u.saturating_sub(1)..=(u + 1).min(img.width() - 1) {
                img.set(x, y, color);
            }
        }
    }
    img
}

fn write_csv(path: &Path, records: &[StepRecord]) -> Result<()> {
    let mut f = crate::output_files::create_file(path)?;
    let mut header = "step,true_x_m,true_y_m,est_x_m,est_y_m,cov_trace_m2,chaos_bits,v,pan_deg,landmarks_observed,surprise_max_bits,person_in_view,person_bearing_deg,person_bearing_next_deg,chosen_pan_deg".to_string();
    if let Some(r) = records.first() {
        for c in &r.decision.candidates {
            header.push_str(&format!(",td_bits_{0},bu_bits_{0}", c.pan_deg));
        }
    }
    writeln!(f, "{header}")?;
    for r in records {
        write!(
            f,
            "{},{:.3},{:.3},{:.4},{:.4},{:.6},{:.4},{},{},{},{:.3},{},{:.2},{:.2},{}",
            r.step,
            r.true_xy.0,
            r.true_xy.1,
            r.mu.0,
            r.mu.1,
            r.cov_trace,
            r.chaos,
            r.decision.v,
            r.pan_deg,
            r.observed,
            r.surprise_max,
            u8::from(r.person_visible),
            r.person_bearing_deg,
            r.person_bearing_next_deg,
            r.decision.pan_deg
        )?;
        for c in &r.decision.candidates {
            write!(f, ",{:.4},{:.4}", c.top_down_bits, c.bottom_up_bits)?;
        }
        writeln!(f)?;
    }
    f.flush()?;
    Ok(())
}

fn angles(records: &[StepRecord]) -> Vec<(f64, f64)> {
    records.iter().map(|r| (r.step as f64, r.decision.pan_deg)).collect()
}

/// Runs the subcommand.
pub fn run(a: PlanArgs) -> Result<()> {
    let What::Corridor(a) = a.what;
    let world = corridor_sim::corridor(&CorridorImages::load(crate::assets::decode)?)?;
    let cfg = RunConfig { steps: a.steps, event: a.event, seed: a.seed, ..RunConfig::default() };
    let frames = a.out.join("frames");
    crate::output_files::create_dir(&frames)?;
    let records = corridor_sim::run(&cfg, &world, |r, frame| -> Result<()> {
        let path = frames.join(format!("step_{:02}.png", r.step));
        Ok(ocellus_io::write_png(path, &annotate(&world, r, frame))?)
    })?;
    write_csv(&a.out.join("steps.csv"), &records)?;
    // Chosen angle per step; with --event, the run without it beside.
    let mut series = vec![plot::Series {
        label: if a.event { "with the person at step 5" } else { "no event" },
        points: angles(&records),
        color: RGBColor(200, 40, 40),
    }];
    let baseline = if a.event {
        Some(corridor_sim::run(&RunConfig { event: false, ..cfg.clone() }, &world, |_, _| -> Result<()> { Ok(()) })?)
    } else {
        None
    };
    if let Some(b) = &baseline {
        series.push(plot::Series { label: "no event", points: angles(b), color: RGBColor(30, 90, 200) });
    }
    plot::draw(
        &a.out.join("angles.png"),
        &plot::Plot {
            title: "chosen camera pan per step",
            x_label: "step (0.5 m each)",
            y_label: "pan (degrees, left positive)",
            series: &series,
            threshold: None,
            y_range: Some((-95.0, 95.0)),
        },
    )?;
    let k = cfg.event_step.min(records.len().saturating_sub(1));
    if let Some(r) = records.get(k) {
        let pts = |f: fn(&ocellus_attention::planning::Candidate) -> f64| {
            r.decision.candidates.iter().map(|c| (c.pan_deg, f(c))).collect::<Vec<_>>()
        };
        let title =
            format!("information gain over the pan at step {k} (chaos {:.2} bits, v = {})", r.chaos, r.decision.v);
        let series = [
            plot::Series { label: "top-down I_td", points: pts(|c| c.top_down_bits), color: RGBColor(30, 90, 200) },
            plot::Series { label: "bottom-up I_bu", points: pts(|c| c.bottom_up_bits), color: RGBColor(200, 40, 40) },
        ];
        plot::draw(
            &a.out.join(format!("gains_step{k}.png")),
            &plot::Plot {
                title: &title,
                x_label: "pan (degrees, left positive)",
                y_label: "bits",
                series: &series,
                threshold: None,
                y_range: None,
            },
        )?;
    }
    outln!("step  x(m)  chaos(bits)  v  pan -> chosen (deg)  landmarks  cov trace (m^2)");
    for r in &records {
        outln!(
            "{:>4} {:>5.1} {:>12.3} {:>2} {:>5} -> {:>6} {:>10} {:>16.5}",
            r.step,
            r.true_xy.0,
            r.chaos,
            r.decision.v,
            r.pan_deg,
            r.decision.pan_deg,
            r.observed,
            r.cov_trace
        );
    }
    if let Some(b) = &baseline {
        let v: Vec<String> = b.iter().map(|r| format!("{}", r.decision.pan_deg)).collect();
        outln!("without the event, chosen pans: {}", v.join(" "));
    }
    outln!("wrote frames/, steps.csv, angles.png, gains_step{k}.png in {}", a.out.display());
    Ok(())
}
