//! `auto`: the graph a scene renders with, chosen by measured error rather than by default
//! (docs/auto.md). Each candidate graph renders a short pilot of the scene; the error estimate
//! of each pilot ([`super::error_estimate`], which needs no reference) is carried forward to the
//! length of the whole render, and the candidate predicted to end with the least error wins and
//! goes on from its pilot, so the winner's pilot is not lost.
//!
//! A pilot's estimate splits into noise and the photon kernels' squared bias. Noise falls as
//! 1/t; the squared bias as r^4, where progressive photon mapping's radius shrinks as
//! r^2 ~ i^-(1 - alpha) (Hachisuka and Jensen 2009; Knaus and Zwicker 2011), so as
//! t^-2(1 - alpha), t^-0.6 for the bundled graphs' alpha 0.7. A candidate whose error the
//! estimate cannot see (a path tracer on a scene with caustics from point lights, which it
//! never samples) is left out.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use crate::Error;
use crate::render::{Budget, ErrorReport, Renderer};

/// The name that asks for the choice, where a graph is named.
pub const AUTO: &str = "auto";

/// The bundled graphs `auto` chooses among, in the order they are piloted: the hybrid (the
/// default before `auto`, so that where a time budget's share for pilots is spent on the first
/// one, what renders is what rendered before), path tracing, and the hybrid with probabilistic
/// PPM at the first diffuse vertex.
pub const CANDIDATES: &[&str] = &["hybrid", "pt", "hybrid_pppm"];

/// The candidate rendered when none can be judged (every estimate missing).
pub const FALLBACK: &str = "hybrid";

/// The share of a time budget the pilots take together, their preparation and shader
/// compilation included: once it is spent, the candidates not yet piloted are left out.
pub const PILOT_SHARE: f64 = 0.1;

/// Least iterations of a pilot: two halves of four, as a target error needs before it may end a
/// render, so that one lucky pair of iterations does not decide.
pub const MIN_PILOT_ITERATIONS: u64 = 8;

/// Least samples per pixel a budget without seconds must ask for to be piloted: the losing
/// pilots' [`MIN_PILOT_ITERATIONS`] each then cost at most a quarter of it. Below, the choice
/// would cost more than it could gain, and [`FALLBACK`] renders.
pub const MIN_PILOTED_SPP: u64 = 64;

/// How the photon kernels' squared bias falls with time: t^-2(1 - alpha) at alpha 0.7.
const BIAS_EXPONENT: f64 = 0.6;

/// Whether `choose` pilots the candidates for `budget`: not for fewer than
/// [`MIN_PILOTED_SPP`] samples and no seconds.
pub fn pilots_for(budget: Budget) -> bool {
    budget.seconds.is_some() || budget.spp.is_none_or(|s| s >= MIN_PILOTED_SPP)
}

/// Whether `graph` (a `--graph` argument) asks for the choice.
pub fn is_auto(graph: &std::path::Path) -> bool {
    graph.as_os_str() == AUTO
}

/// One candidate's pilot.
#[derive(Debug, Clone)]
pub struct Pilot {
    pub graph: &'static str,
    /// Building its renderer: pipelines, buffers (the scene is shared).
    pub prepare_seconds: f64,
    /// Rendering it, its error estimate included.
    pub render_seconds: f64,
    /// What its iterations cost at the pace of all but the first (which compiles the shaders
    /// the driver has not cached): the time its estimate is judged at.
    pub paced_seconds: f64,
    pub iterations: u64,
    /// Its estimate at the pilot's end.
    pub estimate: Option<ErrorReport>,
    /// Its estimate carried to the horizon ([`ChoiceReport::horizon`]).
    pub predicted: Option<f64>,
    /// Why it cannot be chosen, where it cannot.
    pub excluded: Option<String>,
}

/// What `choose` settled: the winner's renderer, rendered as far as its pilot, and why.
pub struct Choice<'a, X> {
    pub renderer: Renderer<'a>,
    /// What `prepare` returned with the winner's renderer.
    pub prepared: X,
    pub report: ChoiceReport,
}

/// The graph chosen, the pilots that chose it and the time they took.
#[derive(Debug, Clone)]
pub struct ChoiceReport {
    pub graph: &'static str,
    pub pilots: Vec<Pilot>,
    /// Why the graph was chosen without pilots, where it was.
    pub not_piloted: Option<String>,
    /// Seconds of rendering the predictions are made for.
    pub horizon: f64,
    /// Seconds since `choose` started: the pilots with their preparation.
    pub seconds: f64,
}

impl ChoiceReport {
    /// The log line that says what was chosen and the estimates that chose it.
    pub fn summary(&self) -> String {
        if let Some(why) = &self.not_piloted {
            return format!("auto: chose {} without pilots: {why}", self.graph);
        }
        let mut parts = Vec::new();
        for p in &self.pilots {
            let what = match (&p.excluded, p.predicted, p.estimate) {
                (Some(why), ..) => format!("{}: left out ({why})", p.graph),
                (None, Some(predicted), Some(e)) => format!(
                    "{}: {predicted:.2e} (pilot: {:.2e} after {} iterations, {:.2} s)",
                    p.graph, e.relmse, p.iterations, p.paced_seconds
                ),
                _ => format!("{}: no estimate", p.graph),
            };
            parts.push(what);
        }
        format!(
            "auto: chose {} by the estimated relMSE each candidate would reach in {:.1} s of \
             rendering: {}",
            self.graph,
            self.horizon,
            parts.join("; ")
        )
    }
}

/// The error of a pilot that estimated `e` after `seconds` of rendering, carried forward to
/// `horizon` seconds: noise as 1/t, the kernels' squared bias as t^-0.6.
pub fn predicted_error(e: &ErrorReport, seconds: f64, horizon: f64) -> f64 {
    let ratio = (seconds / horizon.max(seconds)).clamp(0.0, 1.0);
    e.variance.max(0.0) * ratio + e.bias.max(0.0) * ratio.powf(BIAS_EXPONENT)
}

/// How long each pilot renders: with a time budget, its share of [`PILOT_SHARE`] of it less its
/// own preparation, and no more than that share has left; otherwise [`MIN_PILOT_ITERATIONS`] or a tenth of the iterations the budget
/// counts, whichever is more. Never past what the budget allows.
#[derive(Debug, Clone, Copy)]
struct PilotLength {
    seconds: Option<f64>,
    iterations: u64,
}

fn pilot_length(
    budget: Budget,
    renderer: &Renderer<'_>,
    prepare_seconds: f64,
    share_left: Option<f64>,
) -> PilotLength {
    let total = renderer.total_iterations(budget);
    let counted = total.map_or(0, |t| (t as f64 * PILOT_SHARE).ceil() as u64);
    let iterations = MIN_PILOT_ITERATIONS
        .max(counted)
        .min(total.unwrap_or(u64::MAX));
    let seconds = budget.seconds.map(|s| {
        let own = s * PILOT_SHARE / CANDIDATES.len() as f64 - prepare_seconds;
        own.min(share_left.unwrap_or(own)).max(0.0)
    });
    PilotLength {
        seconds,
        iterations,
    }
}

/// Renders `renderer`'s pilot: at least its iterations, then on to its seconds, never past the
/// job's own budget. Returns the seconds it took and the seconds its iterations cost at the
/// pace of all but the first: the first compiles what the driver has not cached (measured:
/// 11 s of a hybrid's first pilot on lavapipe with a cold shader cache, 0.05 s warm), a cost the
/// render pays once whichever graph wins.
fn run_pilot(
    renderer: &mut Renderer<'_>,
    length: PilotLength,
    budget: Budget,
    cancel: &AtomicBool,
) -> Result<(f64, f64), Error> {
    let start = Instant::now();
    let per_iteration = renderer.spp_per_iteration().max(1);
    let first = renderer.iterations();
    let iterations = |n: u64| Budget {
        spp: Some(n * per_iteration),
        ..Budget::default()
    };
    renderer.run(cap(iterations(first + 1), budget), cancel, |_, _| {})?;
    let warm = Instant::now();
    let after_first = renderer.iterations();
    renderer.run(
        cap(iterations(length.iterations), budget),
        cancel,
        |_, _| {},
    )?;
    if let Some(seconds) = length.seconds {
        let left = seconds - start.elapsed().as_secs_f64();
        if left > 0.0 {
            let by_time = Budget {
                seconds: Some(left),
                ..Budget::default()
            };
            renderer.run(cap(by_time, budget), cancel, |_, _| {})?;
        }
    }
    let done = renderer.iterations() - first;
    let paced = renderer.iterations() - after_first;
    let wall = start.elapsed().as_secs_f64();
    let seconds = match paced {
        0 => wall,
        _ => warm.elapsed().as_secs_f64() / paced as f64 * done as f64,
    };
    Ok((wall, seconds))
}

/// `pilot` capped by the counts of the job's `budget` (its samples and photons), so that a
/// pilot never renders more than the whole render may.
fn cap(pilot: Budget, budget: Budget) -> Budget {
    let spp = match (pilot.spp, budget.spp) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    Budget {
        spp,
        photons: budget.photons,
        ..pilot
    }
}

/// Prepares each candidate with `prepare`, renders its pilot and keeps the renderer of the one
/// predicted to end with the least error, dropping the others as soon as they lose. A
/// candidate that cannot be prepared for the scene, whose render fails, that has no estimate,
/// or whose estimate cannot see all of its error, is left out with its reason; with none left,
/// [`FALLBACK`] renders (its own error, where it has one, is returned).
pub fn choose<'a, X>(
    budget: Budget,
    cancel: &AtomicBool,
    mut prepare: impl FnMut(&'static str) -> Result<(Renderer<'a>, X), Error>,
) -> Result<Choice<'a, X>, Error> {
    let start = Instant::now();
    if !pilots_for(budget) {
        let spp = budget.spp.unwrap_or(0);
        let (renderer, prepared) = prepare(FALLBACK)?;
        let why =
            format!("{spp} samples per pixel are too few to pilot (at least {MIN_PILOTED_SPP})");
        return Ok(Choice {
            renderer,
            prepared,
            report: ChoiceReport {
                graph: FALLBACK,
                pilots: Vec::new(),
                not_piloted: Some(why),
                horizon: 0.0,
                seconds: start.elapsed().as_secs_f64(),
            },
        });
    }
    let mut pilots = Vec::new();
    // The best so far: its index in pilots, its renderer and what prepare returned with it.
    let mut best: Option<(usize, Renderer<'a>, X)> = None;
    // A time budget's horizon is known; a count's is the time the first candidate judged
    // would take for all of it.
    let mut horizon = budget.seconds.map(|s| s * (1.0 - PILOT_SHARE));
    // A candidate kept to render when none can be judged.
    let mut fallback: Option<(&'static str, Renderer<'a>, X)> = None;
    let mut first_error = None;
    for &graph in CANDIDATES {
        let spent = start.elapsed().as_secs_f64();
        if best.is_some() && budget.seconds.is_some_and(|s| spent >= s * PILOT_SHARE) {
            let why = "the pilots' share of the time budget was spent (preparing and compiling \
                       the graphs before it)";
            pilots.push(left_out(graph, 0.0, why.into()));
            continue;
        }
        let preparing = Instant::now();
        let (mut renderer, extra) = match prepare(graph) {
            Ok(prepared) => prepared,
            Err(e) => {
                pilots.push(left_out(
                    graph,
                    0.0,
                    format!("cannot render this scene: {e}"),
                ));
                first_error.get_or_insert(e);
                continue;
            }
        };
        let prepare_seconds = preparing.elapsed().as_secs_f64();
        let share_left = budget
            .seconds
            .map(|s| s * PILOT_SHARE - start.elapsed().as_secs_f64());
        if renderer.unsampled_light_warning().is_some() {
            let why = "the scene has caustics from point, spot or directional lights, which it \
                       never samples and its estimate cannot see";
            pilots.push(left_out(graph, prepare_seconds, why.into()));
            continue;
        }
        let photons_only = budget.spp.is_none() && budget.seconds.is_none();
        if photons_only && renderer.photons_per_iteration() == 0 {
            let why = "the budget counts photons and it traces none";
            pilots.push(left_out(graph, prepare_seconds, why.into()));
            continue;
        }
        let length = pilot_length(budget, &renderer, prepare_seconds, share_left);
        let (render_seconds, paced_seconds) = match run_pilot(&mut renderer, length, budget, cancel)
        {
            Ok(seconds) => seconds,
            Err(e) => {
                pilots.push(left_out(
                    graph,
                    prepare_seconds,
                    format!("its pilot failed: {e}"),
                ));
                continue;
            }
        };
        let estimate = renderer.error_estimate()?.map(|e| ErrorReport {
            seconds: paced_seconds,
            iterations: renderer.iterations(),
            relmse: e.relmse,
            variance: e.variance,
            bias: e.bias,
        });
        let mut pilot = Pilot {
            graph,
            prepare_seconds,
            render_seconds,
            paced_seconds,
            iterations: renderer.iterations(),
            estimate,
            predicted: None,
            excluded: None,
        };
        let Some(estimate) = estimate else {
            pilot.excluded = Some("no error estimate (fewer than 2 iterations)".into());
            pilots.push(pilot);
            if graph == FALLBACK {
                fallback = Some((graph, renderer, extra));
            }
            continue;
        };
        pilots.push(pilot);
        let index = pilots.len() - 1;
        let horizon =
            *horizon.get_or_insert_with(|| projected_seconds(budget, &renderer, paced_seconds));
        let predicted = predicted_error(&estimate, paced_seconds, horizon);
        pilots[index].predicted = Some(predicted);
        let wins = match &best {
            None => true,
            Some((b, ..)) => pilots[*b].predicted.is_some_and(|b| predicted < b),
        };
        if wins {
            best = Some((index, renderer, extra));
        }
    }
    let (graph, renderer, prepared) = match (best, fallback) {
        (Some((index, renderer, extra)), _) => (pilots[index].graph, renderer, extra),
        (None, Some(kept)) => kept,
        (None, None) => {
            return Err(first_error.unwrap_or_else(|| {
                Error::Other(
                    "auto: none of the candidate graphs could render this scene".to_string(),
                )
            }));
        }
    };
    Ok(Choice {
        renderer,
        prepared,
        report: ChoiceReport {
            graph,
            pilots,
            not_piloted: None,
            horizon: horizon.unwrap_or(0.0),
            seconds: start.elapsed().as_secs_f64(),
        },
    })
}

fn left_out(graph: &'static str, prepare_seconds: f64, why: String) -> Pilot {
    Pilot {
        graph,
        prepare_seconds,
        render_seconds: 0.0,
        paced_seconds: 0.0,
        iterations: 0,
        estimate: None,
        predicted: None,
        excluded: Some(why),
    }
}

/// How long `renderer`, whose pilot took `pilot_seconds`, would take for all the iterations the
/// budget counts (at least the pilot's own time).
fn projected_seconds(budget: Budget, renderer: &Renderer<'_>, pilot_seconds: f64) -> f64 {
    let done = renderer.iterations().max(1) as f64;
    match renderer.total_iterations(budget) {
        Some(total) => pilot_seconds * (total as f64 / done).max(1.0),
        None => pilot_seconds / PILOT_SHARE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(variance: f64, bias: f64) -> ErrorReport {
        ErrorReport {
            seconds: 1.0,
            iterations: 8,
            relmse: variance + bias,
            variance,
            bias,
        }
    }

    /// Noise alone falls as 1/t: 1e-2 after 1 s is 1e-3 after 10 s. Would catch the pilot's
    /// own estimate compared as it is (no carrying forward) or noise carried as t^-0.6.
    #[test]
    fn noise_is_carried_forward_as_one_over_time() {
        let p = predicted_error(&report(1e-2, 0.0), 1.0, 10.0);
        assert!((p / 1e-3 - 1.0).abs() < 1e-12, "{p}");
    }

    /// Squared bias falls as t^-0.6: 1e-2 after 1 s is 1e-2 * 10^-0.6 = 2.51e-3 after 10 s.
    /// A bias carried as 1/t would favour the photon-mapping graphs 4x at ten times the pilot.
    #[test]
    fn kernel_bias_is_carried_forward_more_slowly() {
        let p = predicted_error(&report(0.0, 1e-2), 1.0, 10.0);
        assert!((p / (1e-2 * 10f64.powf(-0.6)) - 1.0).abs() < 1e-12, "{p}");
        // Past the horizon nothing is extrapolated backwards.
        assert_eq!(predicted_error(&report(1e-2, 1e-2), 5.0, 2.0), 2e-2);
    }

    /// A biased candidate that leads at the pilot loses at a long horizon to an unbiased one:
    /// at 1 s, (noise 1e-2, bias 0) against (noise 2e-3, bias 4e-3); at 100 s, 1e-4 against
    /// 2e-5 + 4e-3 * 100^-0.6 = 2.7e-4. The choice depends on the horizon, as it should.
    #[test]
    fn the_ranking_is_made_at_the_horizon() {
        let (pt, hybrid) = (report(1e-2, 0.0), report(2e-3, 4e-3));
        assert!(predicted_error(&hybrid, 1.0, 1.0) < predicted_error(&pt, 1.0, 1.0));
        assert!(predicted_error(&pt, 1.0, 100.0) < predicted_error(&hybrid, 1.0, 100.0));
    }
}
