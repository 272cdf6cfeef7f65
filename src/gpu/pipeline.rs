//! Compute pipelines with bind group layouts made from the bindings `build.rs` reflected out of
//! each shader, bound by the shader's names, and bind groups kept while their resources live.
//!
//! Every kernel's pipelines come from one [`Pipelines`] cache (built on first use, for any
//! combination of defines and `override` constants), so a pass never holds a pipeline array of
//! its own and a resize keeps every compiled pipeline.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

mod generated {
    include!(concat!(env!("OUT_DIR"), "/bindings.rs"));
}

pub(crate) use generated::slots;

/// One `@group(0) @binding(n) var name` of a kernel, as `build.rs` found it. The constants in
/// `slots::<kernel>` are the only way to name one, so a binding the WGSL renames or drops fails
/// the build where it is bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    /// `wgsl/<kernel>.wgsl`.
    pub kernel: &'static str,
    /// The variable's name in the shader.
    pub name: &'static str,
    /// Its binding number.
    pub binding: u32,
}

/// Bind groups kept per pipeline: one per distinct set of resources (ping-pong buffers, several
/// targets of one kernel), the oldest dropped past this many.
const KEPT_BIND_GROUPS: usize = 32;

/// A resource a bind group holds, compared by identity.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Bound {
    Buffer(wgpu::Buffer),
    View(wgpu::TextureView),
}

/// A compute pipeline with its explicit bind group layout and the bind groups made for it.
#[derive(Debug)]
pub(crate) struct Pipeline {
    label: String,
    kernel: &'static str,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// The bindings the entry point uses, in binding order.
    uses: &'static [(u32, wgpu::BindingType)],
    groups: Mutex<Vec<(Vec<Bound>, wgpu::BindGroup)>>,
}

impl Pipeline {
    fn new(
        device: &wgpu::Device,
        kernel: &'static str,
        entry: &str,
        defines: &[&str],
        constants: &[(&str, f64)],
    ) -> Pipeline {
        let file = format!("{kernel}.wgsl");
        let source = super::shader_source(&file, defines);
        let declared = super::preprocess::declared_defines(
            super::shaders::SOURCES.iter().find(|(k, _)| *k == file).map_or("", |(_, v)| *v),
        );
        let mask = declared
            .iter()
            .enumerate()
            .filter(|(_, d)| defines.contains(d))
            .fold(0u32, |m, (i, _)| m | (1 << i));
        let uses = generated::ENTRY_LAYOUTS
            .iter()
            .find(|(k, e, m, _)| *k == kernel && *e == entry && *m == mask)
            .map(|(.., uses)| *uses)
            .unwrap_or_else(|| panic!("build.rs reflected no compute entry `{entry}` in {file}"));
        let label = format!("deep-gbuffer.{kernel}.{entry}");
        let entries: Vec<wgpu::BindGroupLayoutEntry> = uses
            .iter()
            .map(|(binding, ty)| wgpu::BindGroupLayoutEntry {
                binding: *binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: *ty,
                count: None,
            })
            .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(&label),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&format!("deep-gbuffer.{kernel}")),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&label),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        });
        Pipeline { label, kernel, pipeline, layout, uses, groups: Mutex::new(Vec::new()) }
    }

    /// The bind group of `buffers` (by slot; slots this entry does not use are ignored, so one
    /// list can serve every entry of a kernel), made on first use and kept while it is used.
    pub(crate) fn bind(
        &self,
        device: &wgpu::Device,
        buffers: &[(Slot, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let bound: Vec<(Slot, Bound)> =
            buffers.iter().map(|(s, b)| (*s, Bound::Buffer((*b).clone()))).collect();
        self.bind_resources(device, &bound)
    }

    /// [`bind`](Pipeline::bind) with one storage texture view besides the buffers.
    pub(crate) fn bind_with_view(
        &self,
        device: &wgpu::Device,
        buffers: &[(Slot, &wgpu::Buffer)],
        view: (Slot, &wgpu::TextureView),
    ) -> wgpu::BindGroup {
        let mut bound: Vec<(Slot, Bound)> =
            buffers.iter().map(|(s, b)| (*s, Bound::Buffer((*b).clone()))).collect();
        bound.push((view.0, Bound::View(view.1.clone())));
        self.bind_resources(device, &bound)
    }

    fn bind_resources(&self, device: &wgpu::Device, given: &[(Slot, Bound)]) -> wgpu::BindGroup {
        debug_assert!(
            given.iter().all(|(s, _)| s.kernel == self.kernel),
            "{}: a binding of another kernel",
            self.label
        );
        let key: Vec<Bound> = self
            .uses
            .iter()
            .map(|(binding, _)| {
                given
                    .iter()
                    .find(|(s, _)| s.binding == *binding)
                    .map(|(_, r)| r.clone())
                    .unwrap_or_else(|| {
                        panic!("{} uses binding {binding}, which was not given", self.label)
                    })
            })
            .collect();
        for ((_, ty), resource) in self.uses.iter().zip(&key) {
            if let (
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only },
                    ..
                },
                Bound::Buffer(buffer),
            ) = (ty, resource)
            {
                super::traffic::bound(buffer, !read_only);
            }
        }
        let mut groups = self.groups.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(i) = groups.iter().position(|(k, _)| *k == key) {
            // Most recently used last.
            let entry = groups.remove(i);
            let group = entry.1.clone();
            groups.push(entry);
            return group;
        }
        let entries: Vec<wgpu::BindGroupEntry> = self
            .uses
            .iter()
            .zip(&key)
            .map(|((binding, _), resource)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: match resource {
                    Bound::Buffer(b) => b.as_entire_binding(),
                    Bound::View(v) => wgpu::BindingResource::TextureView(v),
                },
            })
            .collect();
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.label),
            layout: &self.layout,
            entries: &entries,
        });
        if groups.len() == KEPT_BIND_GROUPS {
            groups.remove(0);
        }
        groups.push((key, group.clone()));
        group
    }

    /// Binds `buffers` and dispatches `groups` workgroups.
    pub(crate) fn dispatch(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        buffers: &[(Slot, &wgpu::Buffer)],
        groups: (u32, u32),
    ) {
        let group = self.bind(device, buffers);
        self.dispatch_group(pass, &group, groups);
    }

    /// Dispatches `groups` workgroups with a bind group made by [`bind`](Pipeline::bind).
    pub(crate) fn dispatch_group(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        group: &wgpu::BindGroup,
        groups: (u32, u32),
    ) {
        self.set(pass, group);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }

    fn set(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
    }

    /// Binds `buffers` and dispatches one 8x8 workgroup per 8x8 pixels of `size` (every
    /// per-pixel kernel uses `@workgroup_size(8, 8)`).
    pub(crate) fn dispatch_pixels(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        buffers: &[(Slot, &wgpu::Buffer)],
        size: (u32, u32),
    ) {
        self.dispatch(device, pass, buffers, (size.0.div_ceil(8), size.1.div_ceil(8)));
    }

    /// Binds `buffers` and dispatches with the arguments at `offset` in `args`.
    pub(crate) fn dispatch_indirect(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        buffers: &[(Slot, &wgpu::Buffer)],
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        self.set(pass, &self.bind(device, buffers));
        pass.dispatch_workgroups_indirect(args, offset);
    }

    fn forget_bind_groups(&self) {
        self.groups.lock().unwrap_or_else(PoisonError::into_inner).clear();
    }
}

type Key = (&'static str, &'static str, Vec<&'static str>, Vec<(&'static str, u64)>);

/// Every pipeline of a renderer, built on first use.
#[derive(Debug, Default)]
pub(crate) struct Pipelines {
    map: Mutex<HashMap<Key, Arc<Pipeline>>>,
}

impl Pipelines {
    /// The pipeline of `entry` in `wgsl/<kernel>.wgsl` with `defines` and `override`
    /// `constants`.
    pub(crate) fn get(
        &self,
        device: &wgpu::Device,
        kernel: &'static str,
        entry: &'static str,
        defines: &[&'static str],
        constants: &[(&'static str, f64)],
    ) -> Arc<Pipeline> {
        let mut sorted = defines.to_vec();
        sorted.sort_unstable();
        let key: Key =
            (kernel, entry, sorted, constants.iter().map(|(n, v)| (*n, v.to_bits())).collect());
        let mut map = self.map.lock().unwrap_or_else(PoisonError::into_inner);
        map.entry(key)
            .or_insert_with(|| Arc::new(Pipeline::new(device, kernel, entry, defines, constants)))
            .clone()
    }

    /// Drops every kept bind group (their resources are about to be replaced).
    pub(crate) fn forget_bind_groups(&self) {
        let map = self.map.lock().unwrap_or_else(PoisonError::into_inner);
        for pipeline in map.values() {
            pipeline.forget_bind_groups();
        }
    }
}
