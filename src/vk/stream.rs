//! Streams: named, in-order lanes of GPU work mapped onto the device's queues.
//!
//! The engine speaks of streams, not queues. Each stream is in order (every submission
//! waits for the stream's previous one) and owns a timeline semaphore; order *between*
//! streams is expressed only as waits on [`TimelinePoint`]s. Streams map onto distinct
//! queues where the device has them and share one queue where it has one (lavapipe), in
//! which case the timeline waits still give the same ordering.

use std::sync::Arc;

use ash::vk;
use serde::Serialize;

use super::physical::PhysicalDeviceInfo;

/// The engine's named streams.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum StreamKind {
    /// Primary compute work (ray generation, tracing, shading).
    Main,
    /// First auxiliary compute stream (e.g. direct lighting).
    Aux0,
    /// Second auxiliary compute stream (e.g. connections).
    Aux1,
    /// Uploads and readbacks.
    Transfer,
}

impl StreamKind {
    pub const ALL: [StreamKind; 4] = [Self::Main, Self::Aux0, Self::Aux1, Self::Transfer];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Main => "main",
            Self::Aux0 => "aux0",
            Self::Aux1 => "aux1",
            Self::Transfer => "transfer",
        }
    }
}

/// How streams are placed on queues.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StreamPlacement {
    /// Distinct queues where the device has them (the default).
    #[default]
    Spread,
    /// Every stream on the main queue: used by tests to prove that timeline semaphores,
    /// not queue separation, carry the ordering.
    SingleQueue,
}

/// Where one stream runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct QueueSlot {
    pub family: u32,
    pub index: u32,
}

/// The stream → queue mapping for a device.
#[derive(Clone, Debug, Serialize)]
pub struct StreamMapping {
    /// Indexed by [`StreamKind::index`].
    pub slots: [QueueSlot; 4],
}

impl StreamMapping {
    /// Plans the mapping: main on the first compute family (graphics+compute preferred,
    /// the most capable queue), auxiliary streams on further compute queues (async
    /// compute families first), transfer on a dedicated transfer family where there is
    /// one. A stream with no queue of its own shares main's.
    pub fn plan(info: &PhysicalDeviceInfo, placement: StreamPlacement) -> Self {
        let families = &info.queue_families;
        let main_family = families
            .iter()
            .filter(|f| f.compute && f.count > 0)
            .min_by_key(|f| (!f.graphics, f.index))
            .map(|f| f.index)
            .unwrap_or(0);
        let main = QueueSlot {
            family: main_family,
            index: 0,
        };
        if placement == StreamPlacement::SingleQueue {
            return Self { slots: [main; 4] };
        }
        // Free compute queues in preference order: compute-only families first.
        let mut free: Vec<QueueSlot> = Vec::new();
        let mut compute_families: Vec<_> = families.iter().filter(|f| f.compute).collect();
        compute_families.sort_by_key(|f| (f.graphics, f.index));
        for f in compute_families {
            for q in 0..f.count {
                let slot = QueueSlot {
                    family: f.index,
                    index: q,
                };
                if slot != main {
                    free.push(slot);
                }
            }
        }
        let take = |free: &mut Vec<QueueSlot>| {
            if free.is_empty() {
                main
            } else {
                free.remove(0)
            }
        };
        let aux0 = take(&mut free);
        let aux1 = take(&mut free);
        let transfer = families
            .iter()
            .find(|f| f.transfer && !f.compute && !f.graphics && f.count > 0)
            .map(|f| QueueSlot {
                family: f.index,
                index: 0,
            })
            .unwrap_or_else(|| take(&mut free));
        Self {
            slots: [main, aux0, aux1, transfer],
        }
    }

    pub fn slot(&self, kind: StreamKind) -> QueueSlot {
        self.slots[kind.index()]
    }

    /// Number of queues to create per family.
    pub fn queues_per_family(&self) -> Vec<(u32, u32)> {
        let mut out: Vec<(u32, u32)> = Vec::new();
        for s in &self.slots {
            match out.iter_mut().find(|(f, _)| *f == s.family) {
                Some((_, n)) => *n = (*n).max(s.index + 1),
                None => out.push((s.family, s.index + 1)),
            }
        }
        out
    }

    /// True when every stream shares one queue.
    pub fn is_single_queue(&self) -> bool {
        self.slots.iter().all(|s| *s == self.slots[0])
    }
}

/// A value on a stream's timeline semaphore: "the work submitted up to here is done".
#[derive(Clone, Debug)]
pub struct TimelinePoint {
    pub(crate) semaphore: Arc<TimelineHandle>,
    pub value: u64,
    pub stream: StreamKind,
}

/// A timeline semaphore handle (destroyed by the device at teardown).
#[derive(Debug)]
pub(crate) struct TimelineHandle {
    pub(crate) raw: vk::Semaphore,
}
