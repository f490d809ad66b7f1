//! Losing the GPU and opening another: a WebGL2 context lost and restored, a WebGPU device lost
//! and replaced at once, and the scene traced again on the new device from what the viewer holds.

use super::{EventListener, GpuState, Page, screen_on};
use crate::params::WebBackend;
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::JsCast;

impl Page {
    pub(super) fn webgl_context_lost(&self) -> bool {
        self.backend == WebBackend::WebGl2
            && self.gpu == GpuState::Live
            && matches!(self.canvas.get_context("webgl2"), Ok(Some(context))
                if context.unchecked_ref::<web_sys::WebGl2RenderingContext>().is_context_lost())
    }

    /// Listens for the loss and restoration of the canvas's WebGL2 context. The loss's default
    /// is prevented: without that, the browser never restores it.
    pub(super) fn watch_canvas(page: &Rc<RefCell<Page>>) {
        if page.borrow().backend != WebBackend::WebGl2 {
            return;
        }
        let weak = Rc::downgrade(page);
        let lost = EventListener::new(move |event: web_sys::Event| {
            event.prevent_default();
            if let Some(page) = weak.upgrade() {
                Page::lose(&page, "the GPU was lost (the WebGL2 context was lost)".into());
            }
        });
        let weak = Rc::downgrade(page);
        let restored = EventListener::new(move |_: web_sys::Event| {
            if let Some(page) = weak.upgrade() {
                Page::restore(&page);
            }
        });
        let mut this = page.borrow_mut();
        for (name, listener) in [("webglcontextlost", lost), ("webglcontextrestored", restored)] {
            let _ = this
                .canvas
                .add_event_listener_with_callback(name, listener.as_ref().unchecked_ref());
            this.canvas_listeners.push((name, listener));
        }
    }

    /// Acts on the loss of the current device as soon as wgpu reports it, not at the next
    /// animation frame, which may not come (see [`Page::restore`]).
    pub(super) fn watch_device(page: &Rc<RefCell<Page>>) {
        let (lost, generation) = {
            let this = page.borrow();
            (this.screen.ctx.when_lost(), this.generation)
        };
        let weak = Rc::downgrade(page);
        wasm_bindgen_futures::spawn_local(async move {
            let Some(why) = lost.await else { return };
            let current = weak.upgrade().filter(|page| page.borrow().generation == generation);
            if let Some(page) = current {
                Page::device_lost(&page, why);
            }
        });
    }

    /// wgpu says the device is lost. WebGPU: a new adapter and device at once. WebGL2 waits for
    /// its context's restoration.
    pub(super) fn device_lost(page: &Rc<RefCell<Page>>, why: String) {
        // Heard of twice (by a frame and by the watch's task), it is restored once.
        if Page::lose(page, format!("the GPU was lost ({why})")) && page.borrow().backend == WebBackend::WebGpu {
            Page::restore(page);
        }
    }

    /// The device is gone: nothing is drawn or built until [`Page::restore`] opens another.
    /// Whether the viewer was not lost already (nor disposed).
    pub(super) fn lose(page: &Rc<RefCell<Page>>, why: String) -> bool {
        let mut this = page.borrow_mut();
        if this.disposed || this.gpu == GpuState::Lost {
            return false;
        }
        this.gpu = GpuState::Lost;
        this.player
            .say(format!("{why}; the viewer shows the scene again when it can"));
        this.publish();
        true
    }

    /// Opens a new device on the canvas (the same backend) and builds the tracer of the scene as
    /// it is now (its camera, modes and time) on it, from what the viewer holds: nothing is
    /// fetched again. Requests made meanwhile are built after it.
    pub(super) fn restore(page: &Rc<RefCell<Page>>) {
        let (canvas, backend, size) = {
            let this = page.borrow();
            if this.disposed || this.gpu != GpuState::Lost {
                return;
            }
            (this.canvas.clone(), this.backend, this.screen.size())
        };
        let page = page.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let opened = screen_on(&canvas, Some(backend), size).await;
            let (ctx, request, generation) = {
                let mut this = page.borrow_mut();
                if this.disposed {
                    return;
                }
                match opened {
                    Ok((_, screen)) => {
                        this.screen = screen;
                        this.generation += 1;
                        this.gpu = GpuState::Restoring;
                        (this.screen.ctx.clone(), this.player.restore_request(), this.generation)
                    }
                    Err(why) => {
                        this.player.say(format!("the GPU was lost and no new one opens: {why}"));
                        this.publish();
                        return;
                    }
                }
            };
            Page::watch_device(&page);
            let built = request.build(&ctx).await;
            let waiting = {
                let mut this = page.borrow_mut();
                // Lost again meanwhile: the restoration of the device opened since is the one.
                if this.disposed || this.gpu != GpuState::Restoring || this.generation != generation {
                    return;
                }
                match built {
                    Ok(tracer) => {
                        this.player.restore(tracer);
                        this.gpu = GpuState::Live;
                    }
                    Err(why) => {
                        this.gpu = GpuState::Lost;
                        this.player
                            .say(format!("the GPU was lost and the scene does not trace again: {why}"));
                    }
                }
                this.publish();
                if this.busy || this.gpu != GpuState::Live {
                    None
                } else {
                    this.waiting.take()
                }
            };
            if page.borrow().gpu == GpuState::Live {
                // Drawn now, not at the next animation frame: Firefox (ESR 153) gives a page no
                // animation frame again once a device that presented to one of its canvases is
                // destroyed, a plain WebGPU page too.
                Page::frame(&page);
            }
            if let Some(pending) = waiting {
                Page::build(&page, pending);
            }
        });
    }
}
