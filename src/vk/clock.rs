//! The GPU's clock against the host's: VK_KHR/EXT_calibrated_timestamps.
//!
//! A calibration samples the device's timestamp counter and a host clock at one instant.
//! Where the host domain is CLOCK_MONOTONIC (the clock Rust's `Instant` reads on Linux),
//! the sample is exact up to the deviation the driver reports; elsewhere the device
//! domain alone is sampled and bracketed by two `Instant`s, the bracket joining the
//! deviation.

use std::time::{Duration, Instant};

use ash::{ext, khr, vk};

use super::device::Gpu;
use super::error::{CallContext, Result};
use super::instance::Instance;
use super::physical::CalibrationExtension;
use super::stream::StreamKind;

/// One instant on both clocks.
#[derive(Clone, Debug)]
pub struct ClockCalibration {
    /// The host instant of the sample.
    pub host: Instant,
    /// The device's timestamp then, in nanoseconds on the scale of
    /// [`ProfileRecord`](super::ProfileRecord) times (ticks × timestampPeriod).
    pub gpu_ns: f64,
    /// How far apart the two readings may lie, in nanoseconds.
    pub max_deviation_ns: f64,
    /// The extension that took the sample.
    pub extension: &'static str,
    /// The host clock sampled with the device's ("clock-monotonic"), or "instant
    /// bracket" where only the device domain was sampled.
    pub host_domain: &'static str,
}

/// The extension's device-level entry point.
pub(crate) enum Calibrator {
    Khr(khr::calibrated_timestamps::Device),
    Ext(ext::calibrated_timestamps::Device),
}

impl Calibrator {
    pub(crate) fn new(
        instance: &Instance,
        device: &ash::Device,
        extension: CalibrationExtension,
    ) -> Self {
        match extension {
            CalibrationExtension::Khr => Self::Khr(khr::calibrated_timestamps::Device::new(
                &instance.raw,
                device,
            )),
            CalibrationExtension::Ext => Self::Ext(ext::calibrated_timestamps::Device::new(
                &instance.raw,
                device,
            )),
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Self::Khr(_) => "VK_KHR_calibrated_timestamps",
            Self::Ext(_) => "VK_EXT_calibrated_timestamps",
        }
    }

    /// One timestamp per domain, and the maximum deviation between them.
    fn sample(&self, domains: &[vk::TimeDomainKHR]) -> Result<(Vec<u64>, u64)> {
        let infos: Vec<_> = domains
            .iter()
            .map(|&d| vk::CalibratedTimestampInfoKHR::default().time_domain(d))
            .collect();
        // SAFETY: the device was created with the extension enabled, and every domain
        // asked for is one the physical device lists as calibrateable.
        unsafe {
            match self {
                Self::Khr(d) => d.get_calibrated_timestamps(&infos),
                Self::Ext(d) => d.get_calibrated_timestamps(&infos),
            }
        }
        .call("vkGetCalibratedTimestamps")
    }
}

/// CLOCK_MONOTONIC now, in nanoseconds: the clock `Instant` reads on Linux.
#[cfg(any(target_os = "linux", target_os = "android"))]
fn monotonic_ns() -> Option<u64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid clock id and a valid out-pointer.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) } == 0;
    ok.then(|| ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64)
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn monotonic_ns() -> Option<u64> {
    None
}

impl Gpu {
    /// Samples the device's clock and the host's together, or `None` where the device
    /// offers no calibrated timestamps.
    pub fn calibrate_clocks(&self) -> Result<Option<ClockCalibration>> {
        let Some(calibrator) = &self.0.calibrator else {
            return Ok(None);
        };
        let period = self.0.info.limits.timestamp_period_ns as f64;
        let mask = self.stream(StreamKind::Main).timestamp_mask;
        let monotonic = self
            .0
            .info
            .calibrated_time_domains
            .iter()
            .any(|d| d == "clock-monotonic")
            && monotonic_ns().is_some();
        if monotonic {
            let domains = [
                vk::TimeDomainKHR::DEVICE,
                vk::TimeDomainKHR::CLOCK_MONOTONIC,
            ];
            let (ts, deviation) = calibrator.sample(&domains)?;
            // The same clock read again at once gives the sample's place among Instants.
            let now = Instant::now();
            let now_ns = monotonic_ns().unwrap_or(ts[1]);
            let host = now
                .checked_sub(Duration::from_nanos(now_ns.saturating_sub(ts[1])))
                .unwrap_or(now);
            return Ok(Some(ClockCalibration {
                host,
                gpu_ns: (ts[0] & mask) as f64 * period,
                max_deviation_ns: deviation as f64,
                extension: calibrator.name(),
                host_domain: "clock-monotonic",
            }));
        }
        let before = Instant::now();
        let (ts, deviation) = calibrator.sample(&[vk::TimeDomainKHR::DEVICE])?;
        let after = Instant::now();
        let half = (after - before) / 2;
        Ok(Some(ClockCalibration {
            host: before + half,
            gpu_ns: (ts[0] & mask) as f64 * period,
            max_deviation_ns: deviation as f64 + half.as_nanos() as f64,
            extension: calibrator.name(),
            host_domain: "instant bracket",
        }))
    }
}
