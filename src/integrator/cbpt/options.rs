//! CBPT's parameters: the population sizes N_C, N_L and N_T (§3, defaults of §6), the
//! batch size of the GPU combination (§4) and where the combination runs.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// N_C of the paper's tests (§6).
pub const DEFAULT_CAMERA_PATHS: u32 = 2000;
/// N_L of the paper's tests.
pub const DEFAULT_LIGHT_PATHS: u32 = 15;
/// N_T of the paper's tests.
pub const DEFAULT_LIGHT_TRACED: u32 = 1500;
/// Linking segments per GPU batch (a multiple of 32: visibility is packed by words).
pub const DEFAULT_BATCH: u32 = 1 << 17;
/// The largest batch: its rays, hits and results stay well inside a 128 MiB binding.
pub const MAX_BATCH: u32 = 1 << 22;
/// The most paths of each population of a step (N_C, N_L, N_T): far past the paper's
/// 2000, 15 and 1500. A million light-traced paths take about 0.2 GB of host memory
/// (measured on the Cornell box); without a bound, N_T = 4·10⁹ ran the host out of memory.
pub const MAX_POPULATION: u32 = 1 << 20;

/// N_C: camera paths per step, given or from Equation 4.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum CameraPaths {
    Fixed(u32),
    /// Chosen by Equation 4 from the measured times of a BPT pair and of a CBPT step
    /// of [`DEFAULT_CAMERA_PATHS`] × N_L pairs (see `calibrate`).
    Equation4,
}

impl CameraPaths {
    /// The number given, if one was (not `auto`).
    pub fn fixed(self) -> Option<u32> {
        match self {
            Self::Fixed(n) => Some(n),
            Self::Equation4 => None,
        }
    }
}

impl Default for CameraPaths {
    fn default() -> Self {
        Self::Fixed(DEFAULT_CAMERA_PATHS)
    }
}

impl fmt::Display for CameraPaths {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Fixed(n) => write!(f, "{n}"),
            Self::Equation4 => f.write_str("auto"),
        }
    }
}

impl FromStr for CameraPaths {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Self::Equation4);
        }
        match s.parse::<u32>() {
            Ok(n) if n >= 1 => Ok(Self::Fixed(n)),
            _ => Err(format!(
                "'{s}' is not a number of camera paths (1 or more) or 'auto'"
            )),
        }
    }
}

impl From<CameraPaths> for String {
    fn from(c: CameraPaths) -> String {
        c.to_string()
    }
}

impl TryFrom<String> for CameraPaths {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

/// Where the linking segments' visibility and shading are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Combination {
    /// The GPU kernels of §4, in double-buffered batches (visibility through the tracer).
    #[default]
    Gpu,
    /// Their CPU twins on every core (the CPU BVH for visibility): the all-CPU baseline
    /// of Table 1, and CBPT without a device.
    Cpu,
}

impl FromStr for Combination {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "gpu" => Ok(Self::Gpu),
            "cpu" => Ok(Self::Cpu),
            _ => Err(format!("unknown combination '{s}' (choose gpu or cpu)")),
        }
    }
}

impl fmt::Display for Combination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Gpu => "gpu",
            Self::Cpu => "cpu",
        })
    }
}

/// The user's CBPT settings (`--cbpt-*`), kept in render options and checkpoints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct CbptSettings {
    /// N_C: the most camera paths per step.
    pub camera_paths: CameraPaths,
    /// N_L: light paths per step, each combined with every camera path.
    pub light_paths: u32,
    /// N_T: light paths light-traced per step (0: none).
    pub light_traced: u32,
    /// Linking segments per GPU batch.
    pub batch: u32,
    pub combination: Combination,
}

impl Default for CbptSettings {
    fn default() -> Self {
        Self {
            camera_paths: CameraPaths::default(),
            light_paths: DEFAULT_LIGHT_PATHS,
            light_traced: DEFAULT_LIGHT_TRACED,
            batch: DEFAULT_BATCH,
            combination: Combination::Gpu,
        }
    }
}

impl CbptSettings {
    /// Refuses settings CBPT cannot run with, naming the option.
    pub fn check(&self) -> Result<(), String> {
        if self.light_paths == 0 {
            return Err("--cbpt-nl must be at least 1".into());
        }
        let populations = [
            ("--cbpt-nc", self.camera_paths.fixed().unwrap_or(0)),
            ("--cbpt-nl", self.light_paths),
            ("--cbpt-nt", self.light_traced),
        ];
        for (option, paths) in populations {
            if paths > MAX_POPULATION {
                return Err(format!(
                    "{option} {paths} is more than {MAX_POPULATION} paths per step"
                ));
            }
        }
        if self.batch < 32 || self.batch > MAX_BATCH || self.batch % 32 != 0 {
            return Err(format!(
                "--cbpt-batch {} must be a multiple of 32 between 32 and {MAX_BATCH}",
                self.batch
            ));
        }
        Ok(())
    }
}

/// Everything the integrator takes besides scene, camera and tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CbptOptions {
    pub seed: u64,
    /// Mitsuba's max_depth (< 0: unbounded).
    pub max_depth: i32,
    /// Russian roulette from this vertex on.
    pub rr_depth: u32,
    pub settings: CbptSettings,
    /// Two population couples in flight (Algorithm 2): the CPU samples step t while the
    /// combination of step t − 1 runs. Off: every step waits for its own combination
    /// (the synchronous reference of the benchmark).
    pub pipelined: bool,
}

impl Default for CbptOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            max_depth: -1,
            rr_depth: 5,
            settings: CbptSettings::default(),
            pipelined: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_paths_parse_and_round_trip() {
        assert_eq!("auto".parse(), Ok(CameraPaths::Equation4));
        assert_eq!("2000".parse(), Ok(CameraPaths::Fixed(2000)));
        assert!("0".parse::<CameraPaths>().is_err());
        assert!("x".parse::<CameraPaths>().is_err());
        let s = CbptSettings::default();
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<CbptSettings>(&json).unwrap(), s);
        assert_eq!(serde_json::from_str::<CbptSettings>("{}").unwrap(), s);
    }

    #[test]
    fn bad_settings_are_refused() {
        let ok = CbptSettings::default();
        assert!(ok.check().is_ok());
        for bad in [
            CbptSettings {
                light_paths: 0,
                ..ok
            },
            CbptSettings { batch: 48, ..ok },
            CbptSettings { batch: 0, ..ok },
            CbptSettings {
                batch: MAX_BATCH * 2,
                ..ok
            },
            CbptSettings {
                camera_paths: CameraPaths::Fixed(MAX_POPULATION + 1),
                ..ok
            },
            CbptSettings {
                light_paths: MAX_POPULATION + 1,
                ..ok
            },
            CbptSettings {
                light_traced: u32::MAX,
                ..ok
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
        // The bound itself is taken.
        let most = CbptSettings {
            camera_paths: CameraPaths::Fixed(MAX_POPULATION),
            light_paths: MAX_POPULATION,
            light_traced: MAX_POPULATION,
            ..ok
        };
        assert!(most.check().is_ok());
    }
}
