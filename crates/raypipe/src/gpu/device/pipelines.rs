//! Pipelines compiled once per device. A renderer or a builder made again with the same shader,
//! entry point and bind group layouts takes the pipeline its device already compiled: the tests
//! make hundreds of renderers on one device, the viewer a new one at every change of mode, and
//! compiling the tracer (naga, then the driver) costs more than tracing a small frame.
//!
//! wgpu gives bind group layouts of equal entries one identity, so a pipeline compiled for one
//! renderer's layouts fits every bind group made from layouts of the same entries: the key holds
//! the entries, not the layout objects. A pipeline whose creation failed is still an object; the
//! context forgets every cached pipeline when work in its error scopes fails
//! ([`GpuContext::checked`](super::GpuContext::checked)), so that no failed one is handed out
//! again.

use std::collections::{HashMap, VecDeque};
use std::hash::Hash;
use std::sync::{Arc, Mutex};

/// Pipelines kept per kind: more than the modes and scenes a test run or a viewing session meets
/// at once; past it the oldest go first. Each key holds its shader's source (the tracer's is tens
/// of kilobytes), which a page's heap holds too.
const CAPACITY: usize = 128;

/// What a pipeline is compiled from: the shader's source, the entry point, and the rest of its
/// descriptor written out (the bind group layouts' entries, targets, compilation options).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    source: Arc<str>,
    entry_point: String,
    descriptor: String,
}

impl PipelineKey {
    /// The key of `entry_point` in `source`, compiled as `descriptor` says.
    pub(crate) fn new(source: &Arc<str>, entry_point: &str, descriptor: String) -> Self {
        Self {
            source: source.clone(),
            entry_point: entry_point.to_string(),
            descriptor,
        }
    }
}

/// A device's compiled pipelines, shared by the clones of its context.
#[derive(Clone, Debug, Default)]
pub(crate) struct PipelineCache {
    shelves: Arc<Mutex<Shelves>>,
}

#[derive(Debug, Default)]
struct Shelves {
    render: Shelf<wgpu::RenderPipeline>,
    compute: Shelf<wgpu::ComputePipeline>,
}

#[derive(Debug)]
struct Shelf<P> {
    pipelines: HashMap<PipelineKey, P>,
    /// Keys, oldest first.
    order: VecDeque<PipelineKey>,
}

impl<P> Default for Shelf<P> {
    fn default() -> Self {
        Self {
            pipelines: HashMap::new(),
            order: VecDeque::new(),
        }
    }
}

impl<P: Clone> Shelf<P> {
    fn keep(&mut self, key: PipelineKey, pipeline: &P) {
        if self.pipelines.insert(key.clone(), pipeline.clone()).is_none() {
            self.order.push_back(key);
        }
        while self.order.len() > CAPACITY {
            if let Some(oldest) = self.order.pop_front() {
                self.pipelines.remove(&oldest);
            }
        }
    }
}

impl PipelineCache {
    /// The render pipeline of `key`, compiled by `compile` where the device has none yet.
    pub(crate) fn render(
        &self,
        key: PipelineKey,
        compile: impl FnOnce() -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        self.get_or_compile(key, |s| &mut s.render, compile)
    }

    /// The compute pipeline of `key`, compiled by `compile` where the device has none yet.
    pub(crate) fn compute(
        &self,
        key: PipelineKey,
        compile: impl FnOnce() -> wgpu::ComputePipeline,
    ) -> wgpu::ComputePipeline {
        self.get_or_compile(key, |s| &mut s.compute, compile)
    }

    /// Pipelines kept, render and compute.
    pub(crate) fn len(&self) -> usize {
        let shelves = self.lock();
        shelves.render.pipelines.len() + shelves.compute.pipelines.len()
    }

    /// Forgets every pipeline: one compiled since the last clear may have failed.
    pub(crate) fn clear(&self) {
        *self.lock() = Shelves::default();
    }

    fn get_or_compile<P: Clone>(
        &self,
        key: PipelineKey,
        shelf: impl Fn(&mut Shelves) -> &mut Shelf<P>,
        compile: impl FnOnce() -> P,
    ) -> P {
        if let Some(pipeline) = shelf(&mut self.lock()).pipelines.get(&key) {
            return pipeline.clone();
        }
        // Compiled without the lock: other threads' renderers need not wait for this one.
        let pipeline = compile();
        shelf(&mut self.lock()).keep(key, &pipeline);
        pipeline
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Shelves> {
        // A thread that panicked while holding the lock left whole maps behind.
        self.shelves.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(entry_point: &str) -> PipelineKey {
        PipelineKey::new(&Arc::from("@compute fn main() {}"), entry_point, String::new())
    }

    #[test]
    fn a_shelf_keeps_the_newest_pipelines() {
        let mut shelf = Shelf::default();
        for i in 0..CAPACITY + 10 {
            shelf.keep(key(&format!("k{i}")), &i);
        }
        // Kept again: no second place in the order.
        shelf.keep(key("k20"), &20);
        assert_eq!(shelf.pipelines.len(), CAPACITY);
        assert_eq!(shelf.order.len(), CAPACITY);
        assert!(!shelf.pipelines.contains_key(&key("k9")), "the oldest went first");
        assert_eq!(shelf.pipelines.get(&key("k10")), Some(&10));
        assert_eq!(
            shelf.pipelines.get(&key(&format!("k{}", CAPACITY + 9))),
            Some(&(CAPACITY + 9))
        );
    }
}
