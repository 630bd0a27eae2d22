//! The step loop of CBPT's Algorithm 2 keeps the CPU and the device busy at once (Fig. 4):
//! while the device combines step t, the CPU thread combines step t − 1 and samples
//! step t + 1. The property is tested by ordering, not by timing: an evaluator whose
//! `gpu_comp_async` (`Evaluator::launch`) runs the combination before it returns — as on
//! a device whose submissions execute in the submitting thread, lavapipe — refuses to
//! return until the CPU thread has begun sampling the next step (seen through the
//! `cbpt sample` span, through a global subscriber: the test runs alone in a process of
//! its own). A loop that waited for step t's combination before it let the
//! CPU thread go on would never get there; the evaluator then gives up with an error.
//! The image is the one of the plain CPU combination, pipelined or not.

use crate::common;

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use splitray::bidir::CpuScene;
use splitray::integrator::cbpt::layout::{CombinationData, Tables};
use splitray::integrator::cbpt::pipeline::{run_steps, Evaluator};
use splitray::integrator::cbpt::{
    CameraPaths, CbptOptions, CbptSettings, Combination, CpuEvaluator, Setup,
};
use splitray::integrator::IntegratorError;
use splitray::scene::builtin;
use tracing::span::{Attributes, Id};
use tracing::Subscriber;
use tracing_subscriber::layer::{Context, Layer, SubscriberExt};

/// How many `cbpt sample` spans (population couples) the CPU thread has begun.
#[derive(Clone, Default)]
struct Sampled(Arc<(Mutex<u64>, Condvar)>);

impl Sampled {
    /// Waits until `n` couples were begun; false after `timeout`.
    fn wait_for(&self, n: u64, timeout: Duration) -> bool {
        let (count, changed) = &*self.0;
        let guard = count.lock().unwrap();
        let (guard, _) = changed
            .wait_timeout_while(guard, timeout, |c| *c < n)
            .unwrap();
        *guard >= n
    }
}

impl<S: Subscriber> Layer<S> for Sampled {
    fn on_new_span(&self, attrs: &Attributes<'_>, _: &Id, _: Context<'_, S>) {
        if attrs.metadata().name() == "cbpt sample" {
            let (count, changed) = &*self.0;
            *count.lock().unwrap() += 1;
            changed.notify_all();
        }
    }
}

/// The CPU combination, launched as a device that runs its work before `launch`
/// returns, and only once the CPU thread has begun the next step's sampling.
struct SynchronousDevice<'a> {
    cpu: CpuEvaluator<'a>,
    sampled: Sampled,
    steps: u64,
    launched: u64,
    /// Steps whose launch saw the CPU thread sampling the next step.
    overlapped: Arc<AtomicU64>,
}

impl Evaluator for SynchronousDevice<'_> {
    type Uploaded = Arc<Tables>;
    type Pending = CombinationData;

    fn upload(&mut self, tables: Arc<Tables>) -> Result<Arc<Tables>, IntegratorError> {
        Ok(tables)
    }

    fn launch(&mut self, tables: Arc<Tables>) -> Result<CombinationData, IntegratorError> {
        self.launched += 1;
        let data = self.cpu.launch(tables)?;
        if self.launched < self.steps {
            // Step t is launched (t = launched − 1): the CPU thread must get to step t + 1.
            if !self
                .sampled
                .wait_for(self.launched + 1, Duration::from_secs(30))
            {
                return Err(IntegratorError::Usage(format!(
                    "the CPU thread did not sample step {} while the device combined step {}",
                    self.launched,
                    self.launched - 1
                )));
            }
            self.overlapped.fetch_add(1, Ordering::Relaxed);
        }
        Ok(data)
    }

    fn finish(&mut self, data: CombinationData) -> Result<CombinationData, IntegratorError> {
        Ok(data)
    }
}

#[test]
fn the_cpu_samples_the_next_step_while_the_device_combines() {
    // The CPU thread's spans are seen through a global subscriber: one per process.
    if !common::process::in_own_process(
        "cbpt_pipeline::the_cpu_samples_the_next_step_while_the_device_combines",
    ) {
        return;
    }
    let sampled = Sampled::default();
    tracing::subscriber::set_global_default(tracing_subscriber::registry().with(sampled.clone()))
        .unwrap();
    let scene = builtin("cornell-box").unwrap();
    let mut camera = scene.camera_frame();
    camera.width = 23;
    camera.height = 17;
    let options = CbptOptions {
        seed: 5,
        max_depth: 6,
        rr_depth: 3,
        settings: CbptSettings {
            camera_paths: CameraPaths::Fixed(100),
            light_paths: 3,
            light_traced: 50,
            combination: Combination::Cpu,
            ..Default::default()
        },
        pipelined: true,
    };
    let setup = Setup::new(CpuScene::new(&scene), &camera, &options, 100, 3).unwrap();
    // 23 × 17 pixels at 4 samples: 16 steps per pass, the last one short.
    let steps = setup.steps(0..2);
    assert_eq!(steps.len(), 32);
    let overlapped = Arc::new(AtomicU64::new(0));
    let mut device = SynchronousDevice {
        cpu: CpuEvaluator {
            scene: &setup.scene,
        },
        sampled: sampled.clone(),
        steps: steps.len() as u64,
        launched: 0,
        overlapped: overlapped.clone(),
    };
    let out = run_steps(&setup.cpu_side(), &mut device, steps.clone(), true, &|| {
        false
    })
    .unwrap();
    assert_eq!(overlapped.load(Ordering::Relaxed), 31);
    assert_eq!(out.times.steps, 32);

    // The same passes combined by the plain CPU evaluator, one step at a time.
    let mut plain = CpuEvaluator {
        scene: &setup.scene,
    };
    let reference = run_steps(&setup.cpu_side(), &mut plain, steps, false, &|| false).unwrap();
    assert_eq!(out.passes, reference.passes);
    assert_eq!(out.counters, reference.counters);
}
