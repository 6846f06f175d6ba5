//! The wgpu device, the pipeline, and render-and-readback of batches of camera views.

use std::sync::{Arc, Mutex, OnceLock};

use wgpu::util::DeviceExt;

use super::mesh::{albedo, Mesh, Vertex};
use super::post;
use super::RenderError;
use crate::network::Network;
use crate::sensor::camera::{CameraFrame, CameraSpec, FrameUse};

use crate::NOMINAL_LIGHT;

/// Direction toward the sun (world, unit after normalising): high, ahead-left of a car driving
/// along `+x`, so faces turned toward an approaching ego vehicle are lit.
const SUN: [f32; 3] = [-0.45, 1.0, -0.3];

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH_OUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
const LABEL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
const ZBUFFER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Near clipping plane, in metres.
const NEAR_M: f32 = 0.05;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    forward: [f32; 4],
    sun: [f32; 4],
    sky: [f32; 4],
    params: [f32; 4],
}

/// A box in the world for the camera: a car, a pedestrian, an obstacle.
pub type RenderObject = crate::actor::VisibleBox;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Instance {
    model: [[f32; 4]; 4],
    tint: [f32; 4],
    /// OR-ed into the vertices' labels: the actor's label, 0 for the static world.
    label: u32,
}

impl Instance {
    fn identity() -> Self {
        Instance {
            model: glam::Mat4::IDENTITY.to_cols_array_2d(),
            tint: [1.0; 4],
            label: 0,
        }
    }

    fn of(o: &RenderObject) -> Self {
        // The unit cube scaled to the box: x along the heading, y up, z across.
        let (l, h, w) = (
            o.size.length_m as f32,
            o.size.height_m as f32,
            o.size.width_m as f32,
        );
        let model = glam::Mat4::from_scale_rotation_translation(
            glam::Vec3::new(l, h, w),
            glam::Quat::from_rotation_y(o.heading_rad as f32),
            glam::Vec3::new(
                o.base_m[0] as f32,
                o.base_m[1] as f32 + h / 2.0,
                o.base_m[2] as f32,
            ),
        );
        Instance {
            model: model.to_cols_array_2d(),
            tint: [o.albedo[0], o.albedo[1], o.albedo[2], 1.0],
            label: crate::segmentation::actor_label(o.class, o.actor),
        }
    }
}

/// Where the camera's vehicle is: chassis centre `[x, y, z]` in metres and heading in rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    /// Chassis centre, world metres.
    pub chassis_m: [f64; 3],
    /// Vehicle heading, rad.
    pub heading_rad: f64,
}

/// The static geometry of one road network, uploaded to the GPU once per world.
#[derive(Clone)]
pub struct SceneGeometry {
    vertices: Arc<wgpu::Buffer>,
    indices: Arc<wgpu::Buffer>,
    index_count: u32,
}

impl SceneGeometry {
    /// Whether `self` and `other` draw from the same GPU buffers (one upload shared).
    pub fn shares_buffers_with(&self, other: &SceneGeometry) -> bool {
        Arc::ptr_eq(&self.vertices, &other.vertices) && Arc::ptr_eq(&self.indices, &other.indices)
    }
}

/// One camera's render targets and readback buffer. Each view renders one frame at a time;
/// many views render together through [`Renderer::render`].
pub struct View {
    camera: CameraSpec,
    usage: FrameUse,
    /// The pixels drawn and read back: [`FrameUse::region_in`].
    region: [u32; 4],
    /// The camera's pixel noise, tabulated once.
    noise: Option<Arc<post::Noise>>,
    /// A frame whose buffers the next frame reuses ([`View::recycle`]).
    spare: Option<CameraFrame>,
    color: wgpu::TextureView,
    color_texture: wgpu::Texture,
    depth_out: wgpu::TextureView,
    depth_texture: wgpu::Texture,
    labels: wgpu::TextureView,
    label_texture: wgpu::Texture,
    zbuffer: wgpu::TextureView,
    readback: wgpu::Buffer,
    padded_row: u32,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    instances: wgpu::Buffer,
    instance_capacity: usize,
}

impl View {
    /// The camera this view renders.
    pub fn camera(&self) -> &CameraSpec {
        &self.camera
    }

    /// What it renders and reads back of each frame.
    pub fn usage(&self) -> FrameUse {
        self.usage
    }

    /// Hands back a frame this view rendered and nobody reads any more: the next frame is
    /// written into its buffers instead of new ones.
    pub fn recycle(&mut self, frame: CameraFrame) {
        self.spare = Some(frame);
    }
}

/// One frame to render: a view of a scene from a pose, with the actors, the light and the fog.
pub struct RenderJob<'a> {
    /// The static world.
    pub scene: &'a SceneGeometry,
    /// The camera's targets.
    pub view: &'a mut View,
    /// The vehicle carrying the camera.
    pub pose: CameraPose,
    /// Cars and pedestrians.
    pub objects: &'a [RenderObject],
    /// Light intensity, `[0, 1]` (see [`NOMINAL_LIGHT`]).
    pub light: f64,
    /// Fog density, `[0, 1]`: extinction `fog · FOG_EXTINCTION_PER_M` per metre, as the lidar
    /// ([`crate::visibility_m`]).
    pub fog: f64,
    /// Simulated time, seconds (stamped on the frame).
    pub t_s: f64,
    /// Seeds the frame's pixel noise (ChaCha8), so noisy frames are reproducible.
    pub noise_seed: u64,
}

/// The offscreen renderer: one wgpu device and pipeline shared by every camera of the
/// process (creating a device costs 55–140 ms; a frame well under 2 ms).
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::RenderPipeline,
    /// The same shader drawing the image only.
    /// The same shader without the depth target, the label target or both.
    partial_pipelines: [wgpu::RenderPipeline; 3],
    layout: wgpu::BindGroupLayout,
    cube: SceneGeometry,
    identity: wgpu::Buffer,
    adapter: String,
}

static SHARED: OnceLock<Result<Arc<Renderer>, RenderError>> = OnceLock::new();

impl Renderer {
    /// Creates a device on the first adapter found: Vulkan (lavapipe on a CPU-only machine),
    /// then GL (llvmpipe). `WGPU_BACKEND` (e.g. `gl`) narrows the choice.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when no adapter exists (install Mesa's
    /// `mesa-vulkan-drivers`), [`RenderError::Device`] when the device cannot be created.
    pub fn new() -> Result<Self, RenderError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN | wgpu::Backends::GL;
        Self::with_instance(desc.with_env())
    }

    /// Creates a device on the first adapter of `backends` only, ignoring `WGPU_BACKEND`
    /// (e.g. `wgpu::Backends::GL` for llvmpipe's OpenGL).
    ///
    /// # Errors
    /// As [`Renderer::new`].
    pub fn with_backends(backends: wgpu::Backends) -> Result<Self, RenderError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends;
        Self::with_instance(desc)
    }

    fn with_instance(desc: wgpu::InstanceDescriptor) -> Result<Self, RenderError> {
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("paracosm"),
            required_limits: wgpu::Limits::downlevel_defaults(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;

        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("paracosm camera"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("paracosm camera"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let (pipeline, partial_pipelines) = pipelines(&device, &pipeline_layout, &shader);
        let cube = upload(&device, &Mesh::unit_cube());
        let identity = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("identity instance"),
            contents: bytemuck::bytes_of(&Instance::identity()),
            usage: wgpu::BufferUsages::VERTEX,
        });
        Ok(Renderer {
            device,
            queue,
            pipeline,
            partial_pipelines,
            layout,
            cube,
            identity,
            adapter: format!("{} ({:?}, {})", info.name, info.backend, info.driver),
        })
    }

    /// The process-wide renderer, created on first use and shared by every simulation and
    /// thread.
    ///
    /// # Errors
    /// As [`Renderer::new`]; a failure is remembered and returned to every later caller.
    pub fn shared() -> Result<Arc<Renderer>, RenderError> {
        SHARED.get_or_init(|| Renderer::new().map(Arc::new)).clone()
    }

    /// The process-wide renderer if one was created and works, without creating one: `None`
    /// when no camera has rendered yet in this process or no adapter was found.
    pub fn in_use() -> Option<Arc<Renderer>> {
        SHARED.get().and_then(|r| r.as_ref().ok().cloned())
    }

    /// The adapter in use, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, llvmpipe)`.
    pub fn adapter(&self) -> &str {
        &self.adapter
    }

    /// Uploads the static world of `network`. A network that is one OpenDRIVE map keeps
    /// its uploaded buffers in the map's cache (`MapRef::mesh`, by the map's pose): every
    /// test of a campaign on that map draws from the same GPU buffers (the renderer's device
    /// is the process's), and only the first uploads them.
    pub fn scene(&self, network: &Network) -> SceneGeometry {
        if let [piece] = network.pieces() {
            if let crate::network::PieceKind::Map { map, .. } = &piece.kind {
                let pose = &piece.pose;
                let key = [pose.x, pose.z, pose.heading_rad].map(f64::to_bits);
                if let Some(g) = map.mesh(key, || Some(upload(&self.device, &Mesh::world(network))))
                {
                    return g;
                }
            }
        }
        upload(&self.device, &Mesh::world(network))
    }

    /// Creates the render targets of `camera`, for frames with every plane of the whole image.
    ///
    /// # Errors
    /// [`RenderError::Camera`] when the camera's values are out of range.
    pub fn view(&self, camera: &CameraSpec) -> Result<View, RenderError> {
        self.view_for(camera, FrameUse::ALL)
    }

    /// Creates the render targets of `camera` for a consumer that reads what `usage` says:
    /// only its region is drawn (a scissor rectangle) and only its planes are read back.
    ///
    /// # Errors
    /// [`RenderError::Camera`] when the camera's values are out of range.
    pub fn view_for(&self, camera: &CameraSpec, usage: FrameUse) -> Result<View, RenderError> {
        camera.validate().map_err(RenderError::Camera)?;
        let region = usage.region_in(camera);
        let size = wgpu::Extent3d {
            width: camera.width,
            height: camera.height,
            depth_or_array_layers: 1,
        };
        let texture = |label, format, usage| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let target = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let color_texture = texture("color", COLOR_FORMAT, target);
        let depth_texture = texture("depth", DEPTH_OUT_FORMAT, target);
        let label_texture = texture("labels", LABEL_FORMAT, target);
        let zbuffer = texture(
            "z-buffer",
            ZBUFFER_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        // The three targets have 4 bytes per pixel; rows are padded to 256 bytes for the copy.
        let padded_row = (4 * region[2]).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let planes = 1 + u64::from(usage.depth) + u64::from(usage.labels);
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: planes * u64::from(padded_row) * u64::from(region[3]),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let globals = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let instance_capacity = 16;
        Ok(View {
            camera: camera.clone(),
            usage,
            region,
            noise: post::Noise::shared(camera.noise_sigma),
            spare: None,
            color: color_texture.create_view(&Default::default()),
            color_texture,
            depth_out: depth_texture.create_view(&Default::default()),
            depth_texture,
            labels: label_texture.create_view(&Default::default()),
            label_texture,
            zbuffer: zbuffer.create_view(&Default::default()),
            readback,
            padded_row,
            globals,
            bind_group,
            instances: self.instance_buffer(instance_capacity),
            instance_capacity,
        })
    }

    fn instance_buffer(&self, capacity: usize) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (capacity * std::mem::size_of::<Instance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Renders every job in one submission and reads the frames back, in the jobs' order.
    /// Batching many cameras amortises the submission and the wait.
    ///
    /// # Errors
    /// [`RenderError::Readback`] when the device fails or is lost.
    pub fn render(&self, jobs: &mut [RenderJob<'_>]) -> Result<Vec<CameraFrame>, RenderError> {
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frames"),
            });
        for job in jobs.iter_mut() {
            self.encode(&mut encoder, job);
        }
        let index = self.queue.submit([encoder.finish()]);
        let failed = Arc::new(Mutex::new(None::<String>));
        for job in jobs.iter() {
            let failed = Arc::clone(&failed);
            job.view
                .readback
                .slice(..)
                .map_async(wgpu::MapMode::Read, move |r| {
                    if let Err(e) = r {
                        *failed.lock().unwrap_or_else(|p| p.into_inner()) = Some(e.to_string());
                    }
                });
        }
        let poll = self.device.poll(wgpu::PollType::Wait {
            submission_index: Some(index),
            timeout: None,
        });
        // Mesa's JIT code ran on this thread (LP_NUM_THREADS=0) with AVX registers.
        crate::simd::clear_upper_vector_state();
        poll.map_err(|e| RenderError::Readback(e.to_string()))?;
        if let Some(e) = failed.lock().unwrap_or_else(|p| p.into_inner()).take() {
            return Err(RenderError::Readback(e));
        }
        let mut frames = Vec::with_capacity(jobs.len());
        for job in jobs.iter_mut() {
            let mut frame = read_frame(job.view, job.t_s)?;
            job.view.readback.unmap();
            post::apply(
                &mut frame,
                job.view.noise.as_deref(),
                &job.view.camera,
                job.noise_seed,
            );
            frames.push(frame);
        }
        Ok(frames)
    }

    /// Renders one frame (a batch of one).
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn render_one(&self, job: RenderJob<'_>) -> Result<CameraFrame, RenderError> {
        let mut jobs = [job];
        Ok(self.render(&mut jobs)?.remove(0))
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder, job: &mut RenderJob<'_>) {
        let camera = &job.view.camera;
        let globals = globals(camera, job);
        self.queue
            .write_buffer(&job.view.globals, 0, bytemuck::bytes_of(&globals));
        let instances: Vec<Instance> = job.objects.iter().map(Instance::of).collect();
        if instances.len() > job.view.instance_capacity {
            job.view.instance_capacity = instances.len().next_power_of_two();
            job.view.instances = self.instance_buffer(job.view.instance_capacity);
        }
        if !instances.is_empty() {
            self.queue
                .write_buffer(&job.view.instances, 0, bytemuck::cast_slice(&instances));
        }
        let view = &*job.view;
        let sky = sky_color(job.light);
        let (depth, labels) = (view.usage.depth, view.usage.labels);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("camera"),
                color_attachments: &[
                    Some(wgpu::RenderPassColorAttachment {
                        view: &view.color,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: sky[0],
                                g: sky[1],
                                b: sky[2],
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                    depth.then_some(wgpu::RenderPassColorAttachment {
                        view: &view.depth_out,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            // The bits of f32 +inf: sky.
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: f64::from(f32::INFINITY.to_bits()),
                                g: 0.0,
                                b: 0.0,
                                a: 0.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                    labels.then_some(wgpu::RenderPassColorAttachment {
                        view: &view.labels,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            // Sky, no actor.
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view.zbuffer,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(match (depth, labels) {
                (true, true) => &self.pipeline,
                (false, false) => &self.partial_pipelines[0],
                (true, false) => &self.partial_pipelines[1],
                (false, true) => &self.partial_pipelines[2],
            });
            let [x, y, w, h] = view.region;
            if [x, y, w, h] != [0, 0, camera.width, camera.height] {
                pass.set_scissor_rect(x, y, w, h);
            }
            pass.set_bind_group(0, &view.bind_group, &[]);
            pass.set_vertex_buffer(0, job.scene.vertices.slice(..));
            pass.set_vertex_buffer(1, self.identity.slice(..));
            pass.set_index_buffer(job.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..job.scene.index_count, 0, 0..1);
            if !instances.is_empty() {
                pass.set_vertex_buffer(0, self.cube.vertices.slice(..));
                pass.set_vertex_buffer(1, view.instances.slice(..));
                pass.set_index_buffer(self.cube.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..self.cube.index_count, 0, 0..instances.len() as u32);
            }
        }
        copy_planes(encoder, view);
    }
}

/// Copies the planes `view` reads, inside its region, into its readback buffer, one after
/// the other (colour, then depth, then labels, each `padded_row × region height` bytes).
fn copy_planes(encoder: &mut wgpu::CommandEncoder, view: &View) {
    let [x, y, w, h] = view.region;
    let size = wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    };
    let plane = u64::from(view.padded_row) * u64::from(h);
    let planes = [
        (&view.color_texture, true),
        (&view.depth_texture, view.usage.depth),
        (&view.label_texture, view.usage.labels),
    ];
    let read = planes.into_iter().filter(|(_, read)| *read);
    for (k, (texture, _)) in read.enumerate() {
        let offset = k as u64 * plane;
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x, y, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &view.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset,
                    bytes_per_row: Some(view.padded_row),
                    rows_per_image: Some(h),
                },
            },
            size,
        );
    }
}

/// The camera's render pipelines, one shader: every plane, then without depth and labels,
/// without labels, without depth (the outputs of a missing target are dropped; the target is
/// neither cleared nor written).
fn pipelines(
    device: &wgpu::Device,
    pipeline_layout: &wgpu::PipelineLayout,
    shader: &wgpu::ShaderModule,
) -> (wgpu::RenderPipeline, [wgpu::RenderPipeline; 3]) {
    let vertex_attributes =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 8 => Uint32];
    let instance_attributes = wgpu::vertex_attr_array![
        3 => Float32x4, 4 => Float32x4, 5 => Float32x4, 6 => Float32x4, 7 => Float32x4,
        9 => Uint32
    ];
    let make_pipeline = |depth: bool, labels: bool| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("paracosm camera"),
            layout: Some(pipeline_layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &vertex_attributes,
                    }),
                    Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<Instance>() as u64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &instance_attributes,
                    }),
                ],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: ZBUFFER_FORMAT,
                depth_write_enabled: Some(true),
                // Reversed Z: near is 1, infinitely far is 0.
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[
                    Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    }),
                    depth.then_some(wgpu::ColorTargetState {
                        format: DEPTH_OUT_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    }),
                    labels.then_some(wgpu::ColorTargetState {
                        format: LABEL_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    }),
                ],
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    let all = make_pipeline(true, true);
    let partial = [
        make_pipeline(false, false),
        make_pipeline(true, false),
        make_pipeline(false, true),
    ];
    (all, partial)
}

fn upload(device: &wgpu::Device, mesh: &Mesh) -> SceneGeometry {
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("vertices"),
        contents: bytemuck::cast_slice(&mesh.vertices),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("indices"),
        contents: bytemuck::cast_slice(&mesh.indices),
        usage: wgpu::BufferUsages::INDEX,
    });
    SceneGeometry {
        vertices: Arc::new(vertices),
        indices: Arc::new(indices),
        index_count: mesh.indices.len() as u32,
    }
}

/// Exposure gain for a light intensity: `light / NOMINAL_LIGHT`, at least 0.
fn exposure(light: f64) -> f64 {
    light.max(0.0) / NOMINAL_LIGHT
}

fn sky_color(light: f64) -> [f64; 3] {
    albedo::SKY.map(|c| (f64::from(c) * exposure(light)).min(1.0))
}

fn globals(camera: &CameraSpec, job: &RenderJob<'_>) -> Globals {
    let (s, c) = job.pose.heading_rad.sin_cos();
    // Vehicle axes in the world: forward (cos, 0, -sin), up (0, 1, 0), right (sin, 0, cos).
    let fwd = glam::DVec3::new(c, 0.0, -s);
    let right = glam::DVec3::new(s, 0.0, c);
    let up = glam::DVec3::Y;
    let [mf, mu, mr] = camera.mount_m;
    let chassis = glam::DVec3::from(job.pose.chassis_m);
    let eye = chassis + fwd * mf + up * mu + right * mr;
    let (ps, pc) = camera.pitch_rad.sin_cos();
    let axis = fwd * pc - up * ps;
    let cam_up = fwd * ps + up * pc;
    let view = glam::dcamera::rh::view::look_to_mat4(eye, axis, cam_up);
    let proj = glam::dcamera::rh::proj::directx::perspective_infinite_reverse(
        camera.vfov_rad(),
        f64::from(camera.width) / f64::from(camera.height),
        f64::from(NEAR_M),
    );
    let sun = glam::Vec3::from(SUN).normalize();
    let v4 = |v: glam::DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
    Globals {
        view_proj: (proj * view).as_mat4().to_cols_array_2d(),
        eye: v4(eye),
        forward: v4(axis),
        sun: [sun.x, sun.y, sun.z, 0.0],
        sky: [albedo::SKY[0], albedo::SKY[1], albedo::SKY[2], 0.0],
        params: [
            exposure(job.light) as f32,
            (job.fog.clamp(0.0, 1.0) * crate::FOG_EXTINCTION_PER_M) as f32,
            camera.far_m as f32,
            0.0,
        ],
    }
}

/// Where a plane's rows lie: the padded row in bytes, the frame's width and the region.
struct Place {
    row: usize,
    full_w: usize,
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
}

/// Copies the plane of 32-bit words that starts at row `plane` of the readback `data` into
/// the region of `out` (`height × width` values), each word through `convert`.
fn copy_words<T>(data: &[u8], at: &Place, plane: usize, out: &mut [T], convert: fn(u32) -> T) {
    for y in 0..at.h {
        let line = &data[(plane + y) * at.row..(plane + y) * at.row + 4 * at.w];
        let start = (at.y0 + y) * at.full_w + at.x0;
        for (b, v) in line.chunks_exact(4).zip(&mut out[start..start + at.w]) {
            *v = convert(u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        }
    }
}

/// The frame in `view`'s mapped readback buffer, written into the buffers of its spare frame
/// when it has one of the same shape.
fn read_frame(view: &mut View, t_s: f64) -> Result<CameraFrame, RenderError> {
    let (width, height) = (view.camera.width, view.camera.height);
    let (full_w, full_h) = (width as usize, height as usize);
    let [x0, y0, w, h] = view.region.map(|v| v as usize);
    let row = view.padded_row as usize;
    let usage = view.usage;
    let mut frame = match view.spare.take() {
        Some(f)
            if (f.width, f.height, f.region) == (width, height, view.region)
                && f.rgb.len() == full_w * full_h * 3
                && f.depth_m.len() == if usage.depth { full_w * full_h } else { 0 }
                && f.labels.len() == if usage.labels { full_w * full_h } else { 0 } =>
        {
            f
        }
        _ => CameraFrame {
            t_s,
            width,
            height,
            region: view.region,
            rgb: vec![0; full_w * full_h * 3],
            depth_m: if usage.depth {
                vec![f32::INFINITY; full_w * full_h]
            } else {
                Vec::new()
            },
            labels: if usage.labels {
                vec![0; full_w * full_h]
            } else {
                Vec::new()
            },
        },
    };
    frame.t_s = t_s;
    let data = view
        .readback
        .slice(..)
        .get_mapped_range()
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let mut plane = 0;
    for y in 0..h {
        let line = &data[y * row..y * row + 4 * w];
        let out = &mut frame.rgb[3 * ((y0 + y) * full_w + x0)..3 * ((y0 + y) * full_w + x0 + w)];
        for (px, rgb) in line.chunks_exact(4).zip(out.chunks_exact_mut(3)) {
            rgb.copy_from_slice(&px[..3]);
        }
    }
    let place = Place {
        row,
        full_w,
        x0,
        y0,
        w,
        h,
    };
    if usage.depth {
        plane += h;
        copy_words(&data, &place, plane, &mut frame.depth_m, f32::from_bits);
    }
    if usage.labels {
        plane += h;
        copy_words(&data, &place, plane, &mut frame.labels, |w| w);
    }
    Ok(frame)
}
