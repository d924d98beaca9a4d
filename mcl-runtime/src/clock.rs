//! The mission clock of the real-time driver: seconds of mission time from
//! a tokio instant, scaled by `--speed`, continued from an offset after a
//! resume. Built on `tokio::time`, so tests can pause and advance it.

use std::time::Duration;
use tokio::time::Instant;

/// Mission time = `offset + (now - start) * speed`.
#[derive(Clone, Copy, Debug)]
pub struct Clock {
    start: Instant,
    speed: f64,
    offset: f64,
}

impl Clock {
    /// A clock reading `offset` now and running `speed` times faster than
    /// the wall clock. A speed that is not a positive number counts as 1.
    pub fn new(speed: f64, offset: f64) -> Self {
        let speed = if speed.is_finite() && speed > 0.0 { speed } else { 1.0 };
        Clock { start: Instant::now(), speed, offset }
    }

    /// The speed factor.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Current mission time.
    pub fn now(&self) -> f64 {
        self.offset + self.start.elapsed().as_secs_f64() * self.speed
    }

    /// The instant at which mission time reaches `t` (now if it has).
    pub fn instant_at(&self, t: f64) -> Instant {
        let real = ((t - self.offset) / self.speed).max(0.0);
        // Beyond ~30 years, sleep "forever" without overflowing.
        self.start + Duration::from_secs_f64(real.min(1e9))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn scales_and_offsets() {
        let c = Clock::new(10.0, 5.0);
        assert!((c.now() - 5.0).abs() < 1e-9);
        tokio::time::sleep(Duration::from_secs(2)).await;
        assert!((c.now() - 25.0).abs() < 1e-6);
        assert_eq!(c.instant_at(45.0), c.start + Duration::from_secs(4));
    }
}
