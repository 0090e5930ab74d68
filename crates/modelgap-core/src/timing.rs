//! How long a stage of the loop took: wall time beside the process's CPU time
//! (every thread), so a run on a shared, busy machine can still be read (its
//! wall time stretches; its CPU time does not).

use std::time::Instant;

use serde::Serialize;

/// CPU time used so far by this process, every thread, user and system (s);
/// `None` where the platform does not say.
#[cfg(unix)]
pub fn cpu_seconds() -> Option<f64> {
    use nix::sys::resource::{UsageWho, getrusage};
    let usage = getrusage(UsageWho::RUSAGE_SELF).ok()?;
    let secs = |t: nix::sys::time::TimeVal| t.tv_sec() as f64 + t.tv_usec() as f64 * 1e-6;
    Some(secs(usage.user_time()) + secs(usage.system_time()))
}

/// CPU time used so far by this process: not measured on this platform.
#[cfg(not(unix))]
pub fn cpu_seconds() -> Option<f64> {
    None
}

/// One stage's time.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct StageTime {
    /// The stage (`calibrate`, `estimate`, `screen`, `confirm`, `pairs`, `judge`).
    pub stage: String,
    /// Wall-clock time (s).
    pub wall_s: f64,
    /// CPU time of the whole process over the stage, every thread (s); `None`
    /// where the platform does not say.
    pub cpu_s: Option<f64>,
}

/// Times stages one after another: each [`Stopwatch::lap`] closes the stage
/// that ran since the last one.
#[derive(Debug)]
pub struct Stopwatch {
    wall: Instant,
    cpu: Option<f64>,
    laps: Vec<StageTime>,
}

impl Default for Stopwatch {
    fn default() -> Self {
        Self::start()
    }
}

impl Stopwatch {
    /// Starts the first stage now.
    pub fn start() -> Stopwatch {
        Stopwatch {
            wall: Instant::now(),
            cpu: cpu_seconds(),
            laps: Vec::new(),
        }
    }

    /// Ends the stage running since the last lap as `stage`, and starts the next.
    pub fn lap(&mut self, stage: &str) {
        let cpu = cpu_seconds();
        self.laps.push(StageTime {
            stage: stage.to_string(),
            wall_s: self.wall.elapsed().as_secs_f64(),
            cpu_s: cpu.zip(self.cpu).map(|(b, a)| (b - a).max(0.0)),
        });
        self.wall = Instant::now();
        self.cpu = cpu;
    }

    /// The stages timed so far.
    pub fn laps(&self) -> &[StageTime] {
        &self.laps
    }

    /// The stages timed, handed over.
    pub fn into_laps(self) -> Vec<StageTime> {
        self.laps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laps_are_in_order_and_never_negative() {
        let mut w = Stopwatch::start();
        let mut x = 0.0_f64;
        for k in 0..200_000 {
            x += f64::from(k).sqrt();
        }
        w.lap("work");
        w.lap("nothing");
        assert!(x > 0.0);
        let laps = w.laps();
        assert_eq!(laps.len(), 2);
        assert_eq!(laps[0].stage, "work");
        assert!(laps.iter().all(|l| l.wall_s >= 0.0));
        if let Some(c) = laps[0].cpu_s {
            assert!(c >= 0.0);
        }
    }
}
