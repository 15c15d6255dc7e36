//! The pass schedule of a render, shared by both backends: how many samples
//! each pass over the film takes and when the render stops. A render's
//! [`PassPlan`] is computed once from its options ([`PassPlan::of`]); each
//! backend runs it as a [`Schedule`], reporting each pass's time and, for a
//! controlled render, the [`Control`]'s verdict on its film.
//!
//! Sample order does not depend on the pass sizes (each pixel's running
//! sums continue in sample order on both backends), so pacing changes how
//! often the host looks at the film, never the image.
//!
//! - A controlled render (`--target-error`, `--adaptive`) takes passes of
//!   [`Control::step`] samples, whole variance batches, and stops when the
//!   control says so or at the cap.
//! - A time-limited render starts with one sample and then takes what fits
//!   the time left at the last pass's rate, growing at most 4x per pass (the
//!   first pass pays cache warm-up); it stops at the last whole pass that fits.
//! - Otherwise the backend's [`Pacing`] decides: the CPU renders everything
//!   in one pass (rayon spreads it over the cores, progress counts tiles);
//!   the GPU sizes dispatches toward a target time from the last one's (a
//!   dispatch that runs for seconds can trip a desktop driver's watchdog and
//!   starves progress reports).

use std::time::Instant;

use crate::adaptive::Control;
use crate::film::RenderOptions;

/// What decides the passes of a render: computed once from its options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassPlan {
    /// Samples per pixel: the whole render, or the cap of a controlled or
    /// time-limited one.
    pub spp: u32,
    /// Seconds of sampling (`RenderOptions::time_limit`).
    pub time_limit: Option<f64>,
    /// `--target-error` / `--adaptive`.
    pub control: Option<Control>,
}

impl PassPlan {
    pub fn of(opts: &RenderOptions) -> Self {
        Self {
            spp: opts.spp,
            time_limit: opts.time_limit,
            control: Control::of(opts),
        }
    }

    /// A plan of `spp` samples in passes of the backend's pacing.
    pub fn whole(spp: u32) -> Self {
        Self {
            spp,
            time_limit: None,
            control: None,
        }
    }
}

/// How a backend paces a render that neither a control nor a time limit
/// paces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pacing {
    /// Every sample in one pass.
    Whole,
    /// Passes of about this many seconds each, sized from the last one's
    /// time, growing at most 4x per pass.
    Target(f64),
}

/// Samples per pass toward `target` seconds from the last pass of
/// `last_count` samples in `last_seconds`: scaled to the target, grown at
/// most 4x per step (the first pass's time includes one-off costs), at
/// least 1, never past `remaining`.
pub fn toward_target(last_count: u32, last_seconds: f64, target: f64, remaining: u32) -> u32 {
    let per_sample = last_seconds / last_count.max(1) as f64;
    let ideal = if per_sample > 0.0 {
        (target / per_sample).floor()
    } else {
        f64::INFINITY
    };
    let grown = (last_count as f64 * 4.0).min(ideal).max(1.0);
    (grown.min(remaining as f64) as u32).max(1).min(remaining)
}

/// Samples per pass for a time-limited render: the passes left in the
/// budget at the last pass's rate, growing at most 4x per pass, never past
/// `remaining`. 0 when the next whole pass of one sample would not fit.
pub fn fit_in_time(last_count: u32, last_seconds: f64, left_seconds: f64, remaining: u32) -> u32 {
    let per_sample = last_seconds / last_count.max(1) as f64;
    let fit = if per_sample > 0.0 {
        (left_seconds / per_sample).floor()
    } else {
        f64::INFINITY
    };
    let n = fit.min(last_count as f64 * 4.0).min(remaining as f64);
    if n >= 1.0 { n as u32 } else { 0 }
}

/// A [`PassPlan`] being run: the samples taken so far and the next pass.
#[derive(Clone, Debug)]
pub struct Schedule {
    plan: PassPlan,
    pacing: Pacing,
    done: u32,
    next: u32,
    started: Instant,
}

impl Schedule {
    /// Start `plan` now (a time limit counts from here).
    pub fn new(plan: PassPlan, pacing: Pacing) -> Self {
        let first = match (plan.control, plan.time_limit, pacing) {
            (Some(c), _, _) => c.step,
            (None, Some(_), _) | (None, None, Pacing::Target(_)) => 1,
            (None, None, Pacing::Whole) => plan.spp,
        };
        Self {
            plan,
            pacing,
            done: 0,
            next: first.min(plan.spp),
            started: Instant::now(),
        }
    }

    /// Samples of the next pass, or None when the render is done.
    pub fn next(&self) -> Option<u32> {
        (self.next > 0).then_some(self.next)
    }

    /// Samples per pixel taken so far.
    pub fn done(&self) -> u32 {
        self.done
    }

    /// The control of a controlled render: after each pass the backend asks
    /// it about its film and passes the answer to [`Schedule::passed`].
    pub fn control(&self) -> Option<&Control> {
        self.plan.control.as_ref()
    }

    /// The pass of [`Schedule::next`] samples took `seconds` (wall clock);
    /// `more`: the control's verdict (ignored without a control).
    pub fn passed(&mut self, seconds: f64, more: bool) {
        let count = self.next;
        self.done += count;
        let left = self.plan.spp - self.done;
        self.next = if left == 0 {
            0
        } else if let Some(c) = self.plan.control {
            if more { c.step.min(left) } else { 0 }
        } else {
            let paced = match self.pacing {
                Pacing::Whole => left,
                Pacing::Target(t) => toward_target(count, seconds, t, left),
            };
            match self.plan.time_limit {
                None => paced,
                Some(limit) => {
                    let time_left = limit - self.started.elapsed().as_secs_f64();
                    paced.min(fit_in_time(count, seconds, time_left, left))
                }
            }
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(plan: PassPlan, pacing: Pacing, seconds_per_sample: f64) -> Vec<u32> {
        let mut s = Schedule::new(plan, pacing);
        let mut passes = Vec::new();
        while let Some(n) = s.next() {
            passes.push(n);
            s.passed(n as f64 * seconds_per_sample, true);
        }
        assert_eq!(s.done(), passes.iter().sum::<u32>());
        passes
    }

    #[test]
    fn toward_target_scales_grows_at_most_4x_and_stops_at_the_end() {
        assert_eq!(toward_target(1, 0.01, 0.25, 1000), 4);
        assert_eq!(toward_target(4, 0.1, 0.25, 1000), 10);
        assert_eq!(toward_target(1, 5.0, 0.25, 1000), 1);
        assert_eq!(toward_target(64, 0.001, 0.25, 3), 3);
        assert_eq!(toward_target(8, 0.0, 0.25, 100), 32);
    }

    #[test]
    fn fit_in_time_takes_what_fits_and_zero_when_nothing_does() {
        assert_eq!(fit_in_time(1, 0.1, 1.0, 100), 4);
        assert_eq!(fit_in_time(8, 0.8, 0.35, 100), 3);
        assert_eq!(fit_in_time(8, 0.8, 0.05, 100), 0);
        assert_eq!(fit_in_time(8, 0.0, 1.0, 5), 5);
    }

    #[test]
    fn plain_renders_take_every_sample() {
        assert_eq!(run(PassPlan::whole(64), Pacing::Whole, 1e-3), vec![64]);
        // 0.25 s target at 10 ms a sample: 1, 4, 16, then 25 a pass.
        assert_eq!(
            run(PassPlan::whole(100), Pacing::Target(0.25), 0.01),
            vec![1, 4, 16, 25, 25, 25, 4]
        );
    }

    #[test]
    fn controlled_renders_take_steps_until_the_control_stops() {
        let opts = RenderOptions {
            spp: 100,
            adaptive: Some(0.1),
            ..RenderOptions::new(8, 8)
        };
        let plan = PassPlan::of(&opts);
        let step = plan.control.unwrap().step;
        let mut s = Schedule::new(plan, Pacing::Target(0.25));
        let mut passes = Vec::new();
        while let Some(n) = s.next() {
            passes.push(n);
            s.passed(1.0, passes.len() < 3);
        }
        assert_eq!(passes, vec![step; 3]);
        // To the cap when the control never stops it; the last pass short.
        let mut s = Schedule::new(plan, Pacing::Whole);
        let mut total = 0;
        while let Some(n) = s.next() {
            total += n;
            s.passed(1.0, true);
        }
        assert_eq!(total, 100);
    }

    #[test]
    fn time_limits_stop_at_the_last_whole_pass_that_fits() {
        let plan = PassPlan {
            spp: 1 << 20,
            time_limit: Some(0.0),
            control: None,
        };
        // Nothing fits after the first pass of one sample.
        assert_eq!(run(plan, Pacing::Whole, 1e-3), vec![1]);
    }
}
