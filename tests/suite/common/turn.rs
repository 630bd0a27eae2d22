//! One test's devices at a time in a test process.
//!
//! libtest runs a binary's tests on parallel threads, each opening its own device. The
//! Vulkan validation layer of Debian 12 (1.3.239) keeps every instance's and device's
//! state in one process-wide map with no lock (`layer_data_map`, looked up by every
//! call it intercepts, inserted into by vkCreateInstance / vkCreateDevice and erased
//! from by their destruction; its GetLayerDataPtr says "We probably should lock here"), so
//! a device opened or closed on one thread while another thread's device is in use
//! makes the other call read a map being rehashed: a rare crash (SIGSEGV, a call through
//! a null pointer inside the layer's vkCreateInstance) or a spurious "Invalid VkDevice".
//! Tests that use no device still run side by side.

use std::ops::Deref;
use std::sync::{Condvar, Mutex, PoisonError};
use std::thread::ThreadId;

use splitray::vk::Gpu;

/// Which thread holds the turn, and how many of its devices hold it.
struct Holder {
    thread: Option<ThreadId>,
    devices: usize,
}

static HOLDER: Mutex<Holder> = Mutex::new(Holder {
    thread: None,
    devices: 0,
});
static RELEASED: Condvar = Condvar::new();

/// The turn of the thread that took it, until dropped. A thread may take it again (a
/// test comparing two devices); a test's own threads use its devices without it, but
/// must not open devices of their own while it holds one (they would wait for ever).
pub struct Turn(());

impl Turn {
    pub fn take() -> Self {
        let me = std::thread::current().id();
        // A test that panicked while holding the turn poisons nothing that matters: the
        // holder's fields are updated before any code that can panic.
        let mut holder = HOLDER.lock().unwrap_or_else(PoisonError::into_inner);
        while holder.thread.is_some_and(|t| t != me) {
            holder = RELEASED
                .wait(holder)
                .unwrap_or_else(PoisonError::into_inner);
        }
        holder.thread = Some(me);
        holder.devices += 1;
        Turn(())
    }
}

impl Drop for Turn {
    fn drop(&mut self) {
        let mut holder = HOLDER.lock().unwrap_or_else(PoisonError::into_inner);
        holder.devices -= 1;
        if holder.devices == 0 {
            holder.thread = None;
            RELEASED.notify_all();
        }
    }
}

/// A test's device: the [`Gpu`], closed before the turn it was opened in is given back.
pub struct TestGpu {
    gpu: Gpu,
    _turn: Turn,
}

impl TestGpu {
    /// Opens a device with `open` in this thread's turn.
    pub fn open(open: impl FnOnce() -> Gpu) -> Self {
        let turn = Turn::take();
        TestGpu {
            gpu: open(),
            _turn: turn,
        }
    }
}

impl Deref for TestGpu {
    type Target = Gpu;
    fn deref(&self) -> &Gpu {
        &self.gpu
    }
}
