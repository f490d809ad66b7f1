//! A lost device (a driver reset, a removed GPU; here `Device::destroy`, which wgpu reports the
//! same way): every operation after it fails with `GpuError::Lost` and its one line, none panics,
//! `when_lost()` wakes its task, and the device the other tests share goes on.

use crate::common::harness::Test;
use crate::common::*;
use raypipe::gpu::{GpuContext, GpuError, Renderer, RendererOptions};
use raypipe::modes::MemoryMode;
use std::future::Future;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::task::{Context, Poll, Wake, Waker};

/// A waker that records that it was woken.
#[derive(Default)]
struct Woken(AtomicBool);

impl Wake for Woken {
    fn wake(self: Arc<Self>) {
        self.0.store(true, Ordering::SeqCst);
    }
}

fn assert_lost<T>(result: Result<T, GpuError>, what: &str) {
    match result {
        Err(GpuError::Lost { why }) => {
            let line = GpuError::Lost { why }.to_string();
            assert!(line.starts_with("the GPU was lost ("), "{what}: {line}");
            assert!(!line.contains('\n'), "{what}: {line}");
        }
        Err(other) => panic!("{what} failed for another reason: {other}"),
        Ok(_) => panic!("{what} succeeded on a lost device"),
    }
}

fn a_lost_device_fails_each_operation_with_one_line(ctx: &GpuContext) {
    // A device of its own on the shared adapter: the shared one must outlive this test.
    let own = pollster::block_on(GpuContext::open(ctx.adapter.clone())).expect("a second device");
    let mut scene = packed("whitted", 16, 12, 1);
    scene.build_bvh();
    let options = RendererOptions {
        memory: MemoryMode::Storage,
        ..Default::default()
    };
    let mut renderer = pollster::block_on(Renderer::new(&own, &scene, options)).expect("a renderer");
    pollster::block_on(renderer.read_frame()).expect("a frame before the loss");
    assert_eq!(own.lost(), None);

    // wgpu hears of the loss at its next poll (here the frame's read-back), as of a driver reset;
    // a task awaiting when_lost() is woken then.
    let mut when_lost = std::pin::pin!(own.when_lost());
    let woken = Arc::new(Woken::default());
    let waker = Waker::from(woken.clone());
    let mut cx = Context::from_waker(&waker);
    assert_eq!(when_lost.as_mut().poll(&mut cx), Poll::Pending);
    own.device.destroy();
    assert_lost(pollster::block_on(renderer.read_frame()), "a frame");
    assert!(own.lost().is_some(), "wgpu did not report the loss");
    assert!(woken.0.load(Ordering::SeqCst), "when_lost's task was not woken");
    assert_eq!(when_lost.as_mut().poll(&mut cx), Poll::Ready(own.lost()));
    assert_lost(pollster::block_on(renderer.read_back()), "a read-back");
    assert_lost(
        pollster::block_on(Renderer::new(&own, &scene, options)),
        "a new renderer",
    );

    // On GL, every device of an adapter shares its one context, in which wgpu binds the vertex
    // array of the device opened last and never binds one again: dropping this device would
    // delete the array the shared device draws with (and its frames would come out dark). It
    // stays, lost, until the tests end.
    drop(renderer);
    if own.info.backend == wgpu::Backend::Gl {
        std::mem::forget(own);
    } else {
        // A device gone without a loss: when_lost() ends with None.
        let other = pollster::block_on(GpuContext::open(ctx.adapter.clone())).expect("a third device");
        let when_lost = other.when_lost();
        drop(other);
        assert_eq!(pollster::block_on(when_lost), None);
    }

    // The shared device is untouched.
    assert_eq!(ctx.lost(), None);
    let mut shared = pollster::block_on(Renderer::new(ctx, &scene, options)).expect("a renderer on the shared device");
    pollster::block_on(shared.read_frame()).expect("a frame on the shared device");
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu a_lost_device_fails_each_operation_with_one_line]
}
