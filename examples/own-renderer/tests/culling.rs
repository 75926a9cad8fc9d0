//! The example renderer with occlude's culling on (the query-driven methods
//! through `Culler`; `hiz`, `roc`, `ioc` and `auto` through `GpuCuller`) draws fewer instances than
//! with culling off, and its images are the same, bit for bit (colour and
//! depth), on every frame of a moving camera, with forward and with reverse
//! Z (with `Depth24Plus`, whose depth cannot be read back, the colour); and
//! the embedding refuses what it cannot cull. Runs on any
//! adapter (lavapipe in CI, with `OCCLUDE_REQUIRE_GPU=1`); skipped with a
//! message where there is none, unless `OCCLUDE_REQUIRE_GPU=1`.

use occlude::glam::{Mat4, Vec3};
use occlude::methods::auto::AutoParams;
use occlude::methods::hiz::{Granularity, HizParams};
use occlude::methods::ioc::IocParams;
use occlude::methods::roc::{RocMode, RocParams};
use occlude::methods::Method;
use occlude::wgpu::embed::{
    Attachments, Culler, Draws, EmbedError, FrameTarget, GpuCuller, IndirectDraw, InstanceDraw, Viewport,
    DRAW_FEATURES, GPU_METHODS, QUERY_METHODS, RASTER_FEATURES,
};
use occlude::{Aabb, Camera, InstanceChange, Scene};
use own_renderer::{open_device_with, Options, Renderer};

/// Frames along the camera's walk.
const FRAMES: u32 = 5;

/// The depth format whose image can be read back.
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A viewport inside the 256 x 256 target, off its corner.
const INSET: Option<Viewport> = Some(Viewport { x: 40, y: 24, width: 192, height: 160 });

/// A device for test `test`, or `None` (after saying why) when there is no
/// adapter and the environment does not require one.
fn device(test: &str) -> Option<(wgpu::Device, wgpu::Queue)> {
    device_with(test, RASTER_FEATURES | DRAW_FEATURES)
}

/// A device as [`device`], with those of `features` the adapter has.
fn device_with(test: &str, features: wgpu::Features) -> Option<(wgpu::Device, wgpu::Queue)> {
    match open_device_with(features) {
        Ok(pair) => Some(pair),
        Err(e) if std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("{test}: OCCLUDE_REQUIRE_GPU=1 but no GPU adapter could be opened: {e}")
        }
        Err(e) => {
            eprintln!("skipping {test}: no GPU adapter ({e})");
            None
        }
    }
}

/// Renders the walk with culling off and with each method (query-driven and
/// GPU-driven), comparing every frame's images (the depth image where it
/// can be read back), and checks that `chcpp` draws fewer instances than
/// culling off on every frame, and `hiz`, `roc` and `ioc` fewer than `vfc` (frustum culling)
/// from the third frame on: its first frame has no depth to test against
/// and draws every instance in the frustum, its second draws those again
/// in its early pass.
fn culling_keeps_the_image(test: &str, reverse_z: bool, depth_format: wgpu::TextureFormat) {
    let Some((device, queue)) = device(test) else { return };
    let options = Options { size: 256, grid: 24, reverse_z, depth_format, meshes: 4, samples: 1, viewport: None };
    culling_keeps_the_image_on(&device, &queue, options);
}

/// [`culling_keeps_the_image`] on `device` with `options`.
fn culling_keeps_the_image_on(device: &wgpu::Device, queue: &wgpu::Queue, options: Options) {
    let depth_format = options.depth_format;
    // Depth with 32-bit float depth and one sample can be read back.
    let float_depth = matches!(depth_format, DEPTH | wgpu::TextureFormat::Depth32FloatStencil8);
    let read_depth = float_depth && options.samples == 1;
    let depth_image = |r: &Renderer| if read_depth { r.depth_image().unwrap() } else { Vec::new() };
    let mut off = Renderer::new(device.clone(), queue.clone(), options);
    let mut reference = Vec::new();
    for frame in 0..FRAMES {
        let t = frame as f32 / (FRAMES - 1) as f32;
        let drawn = off.render(t).unwrap();
        assert_eq!(drawn, u64::from(off.instance_count()));
        let color = off.color_image().unwrap();
        // The images compared show something: walls and, through the gaps,
        // boxes, over the background (the top-left pixel).
        let background = &color[..4];
        let drawn_pixels = color.chunks(4).filter(|p| p != &background).count();
        let area = options.viewport.map_or(options.size * options.size, |v| v.width * v.height);
        assert!(drawn_pixels > area as usize / 10, "frame {frame}: the image is nearly empty ({drawn_pixels} pixels)");
        reference.push((color, depth_image(&off)));
    }
    let mut in_frustum = Vec::new();
    for method in QUERY_METHODS.into_iter().chain(GPU_METHODS) {
        let mut on = Renderer::new(device.clone(), queue.clone(), options);
        on.set_culling(Some(method.parse().unwrap())).unwrap();
        for (frame, (color, depth)) in reference.iter().enumerate() {
            let t = frame as f32 / (FRAMES - 1) as f32;
            let drawn = on.render(t).unwrap();
            let got_color = on.color_image().unwrap();
            let got_depth = depth_image(&on);
            let differing_colors = got_color.chunks(4).zip(color.chunks(4)).filter(|(a, b)| a != b).count();
            assert_eq!(differing_colors, 0, "{method}, frame {frame}: colour pixels differ from culling off");
            assert_eq!(occlude::differing_pixels(&got_depth, depth), 0, "{method}, frame {frame}: depth differs");
            match method {
                "vfc" => in_frustum.push(drawn),
                "chcpp" => assert!(
                    drawn < u64::from(on.instance_count()),
                    "chcpp, frame {frame}: drew {drawn} of {} instances",
                    on.instance_count()
                ),
                "hiz" | "roc" | "ioc" if frame >= 2 => assert!(
                    drawn < in_frustum[frame],
                    "{method}, frame {frame}: drew {drawn} instances, frustum culling {}",
                    in_frustum[frame]
                ),
                _ => {}
            }
        }
    }
}

#[test]
fn culling_keeps_the_image_and_draws_fewer_instances() {
    let test = "culling_keeps_the_image_and_draws_fewer_instances";
    culling_keeps_the_image(test, false, wgpu::TextureFormat::Depth32Float);
}

#[test]
fn culling_keeps_the_image_with_reverse_z() {
    culling_keeps_the_image("culling_keeps_the_image_with_reverse_z", true, wgpu::TextureFormat::Depth32Float);
}

#[test]
fn culling_keeps_the_image_with_depth24plus() {
    culling_keeps_the_image("culling_keeps_the_image_with_depth24plus", false, wgpu::TextureFormat::Depth24Plus);
    culling_keeps_the_image("culling_keeps_the_image_with_depth24plus", true, wgpu::TextureFormat::Depth24Plus);
}

/// Two hundred meshes in two draw groups: each GPU-driven list is drawn
/// with one multi-draw per group, and the images are those of culling off.
#[test]
fn culling_keeps_the_image_of_two_hundred_meshes() {
    let Some((device, queue)) = device("culling_keeps_the_image_of_two_hundred_meshes") else { return };
    let options =
        Options { size: 256, grid: 24, reverse_z: false, depth_format: DEPTH, meshes: 200, samples: 1, viewport: None };
    culling_keeps_the_image_on(&device, &queue, options);
}

/// The culling passes and dispatches of every frame of the walk are the
/// same for one mesh and for two hundred, over the same instances, for
/// `hiz`, `roc` and `ioc`, and the same on every frame; and there are some
/// (render passes for the box tests of `roc` and `ioc`).
#[test]
fn culling_passes_are_the_same_for_one_mesh_and_two_hundred() {
    let Some((device, queue)) = device("culling_passes_are_the_same_for_one_mesh_and_two_hundred") else { return };
    // `auto`'s passes are those of the late test it chooses each frame.
    for method in GPU_METHODS.into_iter().filter(|&m| m != "auto") {
        let [one, many] = [1, 200].map(|meshes| {
            let options = Options {
                size: 256,
                grid: 24,
                reverse_z: false,
                depth_format: DEPTH,
                meshes,
                samples: 1,
                viewport: None,
            };
            let mut renderer = Renderer::new(device.clone(), queue.clone(), options);
            renderer.set_culling(Some(method.parse().unwrap())).unwrap();
            (0..FRAMES)
                .map(|frame| {
                    renderer.render(frame as f32 / (FRAMES - 1) as f32).unwrap();
                    renderer.pass_counts().unwrap()
                })
                .collect::<Vec<_>>()
        });
        assert_eq!(one, many, "{method}: the passes of 1 mesh, then of 200");
        // Counted per frame: the same on every frame of a static scene.
        assert!(one.windows(2).all(|w| w[0] == w[1]), "{method}: {one:?}");
        for counts in &one {
            assert!(counts.compute_passes > 0 && counts.dispatches >= counts.compute_passes, "{method}: {counts:?}");
            assert_eq!(counts.render_passes > 0, method != "hiz", "{method}: {counts:?}");
        }
    }
}

/// Without `MULTI_DRAW_INDIRECT_COUNT` each group's multi-draw runs over
/// all its meshes' commands, those without visible instances empty: the
/// images are still those of culling off.
#[test]
fn culling_keeps_the_image_without_draw_counts() {
    let features = RASTER_FEATURES | wgpu::Features::INDIRECT_FIRST_INSTANCE;
    let Some((device, queue)) = device_with("culling_keeps_the_image_without_draw_counts", features) else { return };
    assert!(!device.features().contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT));
    let options =
        Options { size: 256, grid: 24, reverse_z: false, depth_format: DEPTH, meshes: 20, samples: 1, viewport: None };
    culling_keeps_the_image_on(&device, &queue, options);
}

/// With 4x MSAA (the farthest sample of each pixel in `hiz`'s pyramid,
/// footprints grown to whole pixels, box tests and queries counting
/// samples), a depth-stencil format and a viewport smaller than the target,
/// the resolved images are those of culling off.
#[test]
fn culling_keeps_the_image_with_msaa_in_a_viewport() {
    let Some((device, queue)) = device("culling_keeps_the_image_with_msaa_in_a_viewport") else { return };
    let depth_format = wgpu::TextureFormat::Depth24PlusStencil8;
    let options =
        Options { size: 256, grid: 24, reverse_z: false, depth_format, meshes: 4, samples: 4, viewport: INSET };
    culling_keeps_the_image_on(&device, &queue, options);
}

/// In a viewport smaller than the target, with reverse Z and
/// `Depth32FloatStencil8` (where the adapter has it), colour and depth are
/// those of culling off.
#[test]
fn culling_keeps_the_image_in_a_viewport() {
    let test = "culling_keeps_the_image_in_a_viewport";
    let Some((device, queue)) =
        device_with(test, RASTER_FEATURES | DRAW_FEATURES | wgpu::Features::DEPTH32FLOAT_STENCIL8)
    else {
        return;
    };
    let depth_format = if device.features().contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
        wgpu::TextureFormat::Depth32FloatStencil8
    } else {
        eprintln!("{test}: the adapter lacks DEPTH32FLOAT_STENCIL8; Depth32Float instead");
        DEPTH
    };
    let options =
        Options { size: 256, grid: 24, reverse_z: true, depth_format, meshes: 4, samples: 1, viewport: INSET };
    culling_keeps_the_image_on(&device, &queue, options);
}

/// Several meshes on a device without `INDIRECT_FIRST_INSTANCE` are
/// refused, naming the feature; one mesh needs none. Draws that do not fit
/// the boxes are refused too.
#[test]
fn several_meshes_need_indirect_first_instance() {
    let Some((device, queue)) = device_with("several_meshes_need_indirect_first_instance", wgpu::Features::empty())
    else {
        return;
    };
    let (attachments, _) = one_box();
    let bounds = [Aabb::new(Vec3::ZERO, Vec3::ONE), Aabb::new(Vec3::X * 2.0, Vec3::new(3.0, 1.0, 1.0))];
    let mesh = |first_index| IndirectDraw::Indexed { index_count: 36, first_index, base_vertex: 0 };
    let instances = |meshes: [u32; 2]| meshes.map(|mesh| InstanceDraw { mesh, group: 0 }).to_vec();
    let hiz = Method::Hiz(HizParams::default());
    let new = |draws: Draws| GpuCuller::new(&device, &queue, attachments, &bounds, &hiz, draws);
    match new(Draws::Meshes { meshes: vec![mesh(0), mesh(36)], instances: instances([0, 1]) }).err() {
        Some(EmbedError::Adapter(message)) => assert!(message.contains("INDIRECT_FIRST_INSTANCE"), "{message}"),
        other => panic!("two meshes without the feature: {other:?}"),
    }
    assert!(new(Draws::Meshes { meshes: vec![mesh(0), mesh(36)], instances: instances([1, 1]) }).is_ok());
    assert!(new(mesh(0).into()).is_ok());
    let unknown = Draws::Meshes { meshes: vec![mesh(0)], instances: instances([0, 1]) };
    assert!(matches!(new(unknown).err(), Some(EmbedError::Draws(_))));
}

#[test]
fn the_embedding_refuses_what_it_cannot_cull() {
    let Some((device, queue)) = device("the_embedding_refuses_what_it_cannot_cull") else { return };
    let (attachments, bounds) = one_box();
    let depth_format = attachments.depth;
    let new = |attachments, bounds: &[Aabb], method: &str| {
        Culler::new(&device, &queue, attachments, bounds, method.parse().unwrap()).err()
    };
    assert!(matches!(new(attachments, &bounds, "opt"), Some(EmbedError::Unsupported(_))));
    assert!(matches!(new(attachments, &bounds, "roc"), Some(EmbedError::Unsupported(_))));
    assert!(matches!(new(attachments, &bounds, "hiz"), Some(EmbedError::Unsupported(_))));
    assert!(matches!(new(attachments, &[], "chcpp"), Some(EmbedError::Scene(_))));
    let always = Attachments { compare: wgpu::CompareFunction::Always, ..attachments };
    assert!(matches!(new(always, &bounds, "chcpp"), Some(EmbedError::Attachments(_))));
    let colour_as_depth = Attachments { depth: wgpu::TextureFormat::Rgba8Unorm, ..attachments };
    assert!(matches!(new(colour_as_depth, &bounds, "chcpp"), Some(EmbedError::Attachments(_))));

    let mut culler = Culler::new(&device, &queue, attachments, &bounds, Method::default()).unwrap();
    let view = |format, size| texture_view(&device, format, size, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let depth = view(depth_format, 8);
    let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
    let forward = Camera::from_matrices(Mat4::IDENTITY, Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0), false).unwrap();

    // Views other than the attachments say: an error, nothing drawn.
    let mut drawn = Vec::new();
    let other_depth = view(wgpu::TextureFormat::Depth24Plus, 8);
    let color = view(wgpu::TextureFormat::Rgba8Unorm, 8);
    for wrong in [FrameTarget { depth: &other_depth, ..target }, FrameTarget { color: Some(&color), ..target }] {
        let result = culler.render(&forward, wrong, |_, instances| drawn.extend_from_slice(instances));
        assert!(matches!(result, Err(EmbedError::Attachments(_))), "{result:?}");
    }
    assert!(drawn.is_empty());

    // A reverse-Z camera over a forward depth test is an error, and the
    // frame still draws what is in view.
    let reverse = Camera::from_matrices(Mat4::IDENTITY, Mat4::perspective_infinite_reverse_rh(1.0, 1.0, 0.1), true);
    let mut drawn = Vec::new();
    let result = culler.render(&reverse.unwrap(), target, |_, instances| drawn.extend_from_slice(instances));
    assert!(matches!(result, Err(EmbedError::Device(_))), "{result:?}");
    assert_eq!(drawn, [0]);
}

#[test]
fn the_embedding_counts_the_triangles_it_is_given() {
    let Some((device, queue)) = device("the_embedding_counts_the_triangles_it_is_given") else { return };
    let (attachments, bounds) = one_box();
    let depth = texture_view(&device, attachments.depth, 8, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
    let camera = Camera::from_matrices(Mat4::IDENTITY, Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0), false).unwrap();
    for (counts, triangles) in [(None, 12), (Some([5000]), 5000)] {
        let mut scene = Scene::from_bounds("one box", &bounds).unwrap();
        if let Some(counts) = counts {
            scene = scene.with_triangle_counts(&counts).unwrap();
        }
        let mut culler = Culler::for_scene(&device, &queue, attachments, scene, Method::Vfc).unwrap();
        let stats = culler.render(&camera, target, |_, _| {}).unwrap();
        assert_eq!((stats.draw_calls, stats.triangles), (1, triangles), "counts {counts:?}");
    }
    let wrong = Scene::from_bounds("one box", &bounds).unwrap().with_triangle_counts(&[1, 2]);
    assert!(matches!(wrong, Err(occlude::SceneError::TriangleCounts { given: 2, instances: 1 })));
}

/// The refusal tests' culling input: depth-only `Depth32Float` attachments
/// tested with `Less`, and one box in front of a camera at the origin
/// looking down -z.
fn one_box() -> (Attachments, [Aabb; 1]) {
    let attachments = Attachments {
        color: None,
        depth: wgpu::TextureFormat::Depth32Float,
        compare: wgpu::CompareFunction::Less,
        samples: 1,
    };
    (attachments, [Aabb::new(Vec3::new(-1.0, -1.0, -6.0), Vec3::new(1.0, 1.0, -5.0))])
}

/// An 8 x 8 depth texture of `format` that `hiz` can read, as a view.
fn sampled_depth(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::TextureView {
    texture_view(device, format, 8, wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING)
}

/// A camera at the origin looking down -z, forward depth: [`one_box`]'s
/// box in view.
fn forward_camera() -> Camera {
    Camera::from_matrices(Mat4::IDENTITY, Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0), false).unwrap()
}

/// A view of a new `size` x `size` texture of `format` and `usage`.
fn texture_view(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    size: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::TextureView {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    });
    texture.create_view(&Default::default())
}

#[test]
fn the_gpu_driven_embedding_refuses_what_it_cannot_cull() {
    let Some((device, queue)) = device("the_gpu_driven_embedding_refuses_what_it_cannot_cull") else { return };
    let (attachments, bounds) = one_box();
    let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
    let new = |attachments, bounds: &[Aabb], method: &str| {
        GpuCuller::new(&device, &queue, attachments, bounds, &method.parse().unwrap(), draw).err()
    };
    for method in ["chcpp", "opt"] {
        assert!(matches!(new(attachments, &bounds, method), Some(EmbedError::Unsupported(_))), "{method}");
    }
    // Settings the GPU-driven embedding does not run, and values out of
    // range, are refused by name.
    let node = Method::Hiz(HizParams { granularity: Granularity::Node, ..Default::default() });
    let last = Method::Roc(RocParams { mode: RocMode::Last });
    let ioc_auto = Method::Ioc(IocParams { auto: true, ..Default::default() });
    let cpu_auto = Method::Auto(AutoParams { gpu: false, ..Default::default() });
    let refused = [
        (node, "hiz.granularity=node"),
        (last, "roc.mode=last"),
        (ioc_auto, "ioc.auto=on"),
        (cpu_auto, "auto.gpu=off"),
    ];
    for (method, setting) in refused {
        match GpuCuller::new(&device, &queue, attachments, &bounds, &method, draw).err() {
            Some(EmbedError::UnsupportedSetting(named)) => assert_eq!(named, setting),
            other => panic!("{setting}: {other:?}"),
        }
    }
    let zero = Method::Hiz(HizParams { texels: 0, ..Default::default() });
    let refused = GpuCuller::new(&device, &queue, attachments, &bounds, &zero, draw).err();
    assert!(matches!(refused, Some(EmbedError::Method(_))), "{refused:?}");
    for method in GPU_METHODS {
        assert!(matches!(new(attachments, &[], method), Some(EmbedError::Scene(_))), "{method}");
        let always = Attachments { compare: wgpu::CompareFunction::Always, ..attachments };
        assert!(matches!(new(always, &bounds, method), Some(EmbedError::Attachments(_))), "{method}");
        // A depth-stencil format too: roc's and ioc's box tests hold its
        // stencil read-only as well.
        for depth in [wgpu::TextureFormat::Depth32Float, wgpu::TextureFormat::Depth24PlusStencil8] {
            the_gpu_driven_embedding_draws_its_lists(&device, &queue, method, depth);
        }
    }
}

/// `method` through a [`GpuCuller`] on the one-box scene, depth format
/// `depth_format`: refusals of a pipeline that cannot read the list, of a
/// depth texture `hiz` cannot read and of a camera of the wrong depth
/// order; then the box's way through the lists, drawn by the renderer and
/// by occlude.
fn the_gpu_driven_embedding_draws_its_lists(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    method: &str,
    depth_format: wgpu::TextureFormat,
) {
    let (attachments, bounds) = one_box();
    let attachments = Attachments { depth: depth_format, ..attachments };
    let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
    // A group the pipeline does not have, or whose entry is not a storage
    // buffer at that binding: an error.
    let pipeline = list_pipeline(device, depth_format);
    let bind = |group, binding| {
        let culler = GpuCuller::new(device, queue, attachments, &bounds, &method.parse().unwrap(), draw).unwrap();
        culler.with_list_pipeline(&pipeline, group, binding).err()
    };
    for (group, binding) in [(0, 0), (1, 3), (2, 0)] {
        assert!(matches!(bind(group, binding), Some(EmbedError::Binding(_))), "group {group}, binding {binding}");
    }

    let mut culler = GpuCuller::new(device, queue, attachments, &bounds, &method.parse().unwrap(), draw).unwrap();
    let sampled = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    let depth = texture_view(device, depth_format, 8, sampled);
    let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
    let mut calls = 0;
    let forward = Camera::from_matrices(Mat4::IDENTITY, Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0), false).unwrap();
    if method == "hiz" {
        // A depth texture the pyramid cannot be read from: an error,
        // nothing drawn (roc only renders into it).
        let unsampled = texture_view(device, depth_format, 8, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let result = culler.render(&forward, FrameTarget { depth: &unsampled, ..target }, |_, _| calls += 1);
        assert!(matches!(result, Err(EmbedError::Attachments(_))), "{result:?}");
    }
    // A reverse-Z camera over a forward depth test: an error, nothing drawn.
    let reverse = Camera::from_matrices(Mat4::IDENTITY, Mat4::perspective_infinite_reverse_rh(1.0, 1.0, 0.1), true);
    let result = culler.render(&reverse.unwrap(), target, |_, _| calls += 1);
    assert!(matches!(result, Err(EmbedError::Device(_))), "{result:?}");
    assert_eq!(calls, 0);
    // A frame that can be culled: both lists drawn, the box (in view, in
    // front of an empty depth buffer) in the late list of the first frame
    // and in the early list of the next.
    let mut lists = Vec::new();
    culler.render(&forward, target, |_, list| lists.push(list.index())).unwrap();
    assert_eq!(lists, [0, 1]);
    assert_eq!(culler.read_counts().unwrap(), [0, 1]);
    culler.render(&forward, target, |_, _| {}).unwrap();
    assert_eq!(culler.read_counts().unwrap(), [1, 0]);
    // The same with occlude drawing the lists (non-indexed) with the
    // pipeline, whose draw of the box covers the whole target at the
    // nearest depth (outside the box, against the rules, to be seen): the
    // box drawn late in frame 0 and early in frame 1 hides itself in frame
    // 1's test (its pyramid, or its depth for roc), so frame 2's early list
    // is empty and its late list has it again. Were the lists not drawn,
    // frame 2 would be frame 1.
    let culler = GpuCuller::new(device, queue, attachments, &bounds, &method.parse().unwrap(), draw).unwrap();
    let mut culler = culler.with_list_pipeline(&pipeline, 1, 0).unwrap();
    let ones: Vec<u8> = [1f32; 4].iter().flat_map(|x| x.to_le_bytes()).collect();
    let uniform = wgpu::util::DeviceExt::create_buffer_init(
        device,
        &wgpu::util::BufferInitDescriptor { label: None, contents: &ones, usage: wgpu::BufferUsages::UNIFORM },
    );
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
    });
    let mut setups = 0;
    for expected in [[0, 1], [1, 0], [0, 1]] {
        culler
            .render_lists(&forward, target, |pass| {
                pass.set_bind_group(0, &group, &[]);
                setups += 1;
            })
            .unwrap();
        assert_eq!(culler.read_counts().unwrap(), expected);
    }
    assert_eq!(setups, 6);
}

/// Every GPU-driven method follows an instance that moves out of view and
/// back, hides and shows: from the next frame its lists hold the instance
/// only where its new box is visible. A change naming no instance is an
/// error.
#[test]
fn the_gpu_driven_embedding_follows_moving_instances() {
    let Some((device, queue)) = device("the_gpu_driven_embedding_follows_moving_instances") else { return };
    let (attachments, bounds) = one_box();
    let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
    let depth = sampled_depth(&device, attachments.depth);
    let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
    let forward = forward_camera();
    let behind = Aabb::new(bounds[0].min + Vec3::Z * 10.0, bounds[0].max + Vec3::Z * 10.0);
    for method in GPU_METHODS {
        let mut culler = GpuCuller::new(&device, &queue, attachments, &bounds, &method.parse().unwrap(), draw).unwrap();
        let steps = [
            (vec![], [0, 1]),
            (vec![InstanceChange::to_box(0, &behind)], [0, 0]),
            (vec![InstanceChange::to_box(0, &bounds[0])], [0, 1]),
            (vec![InstanceChange::Hide(0)], [0, 0]),
            (vec![InstanceChange::Show(0)], [0, 1]),
        ];
        for (k, (changes, counts)) in steps.iter().enumerate() {
            culler.update(changes).unwrap();
            culler.render(&forward, target, |_, _| {}).unwrap();
            assert_eq!(culler.read_counts().unwrap(), *counts, "{method}, step {k}");
        }
        assert!(matches!(culler.update(&[InstanceChange::Hide(7)]), Err(EmbedError::Motion(_))), "{method}");
    }
}

/// `auto` in a [`GpuCuller`] tries each of its late tests (`roc`, `hiz`,
/// the frustum alone) within its first frames, timed by timestamps where
/// the device has them and by the wall clock where not; whichever runs,
/// the one box in view is in every frame's lists as the other methods put
/// it (late in the first frame, early after).
#[test]
fn auto_in_the_gpu_driven_embedding_tries_every_late_test() {
    let test = "auto_in_the_gpu_driven_embedding_tries_every_late_test";
    let stamps = RASTER_FEATURES | wgpu::Features::TIMESTAMP_QUERY;
    for features in [RASTER_FEATURES, stamps] {
        let Some((device, queue)) = device_with(test, features) else { return };
        let (attachments, bounds) = one_box();
        let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
        let depth = sampled_depth(&device, attachments.depth);
        let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
        let mut culler = GpuCuller::new(&device, &queue, attachments, &bounds, &"auto".parse().unwrap(), draw).unwrap();
        let mut ran = Vec::new();
        for frame in 0..40 {
            culler.render(&forward_camera(), target, |_, _| {}).unwrap();
            ran.push(culler.late_test().0);
            let expected = if frame == 0 { [0, 1] } else { [1, 0] };
            assert_eq!(culler.read_counts().unwrap(), expected, "frame {frame}, {}", ran[frame]);
        }
        let timed = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        for method in ["roc", "hiz", "vfc"] {
            assert!(ran.contains(&method), "timestamps {timed}: {method} never ran: {ran:?}");
        }
        assert_eq!(ran[0], "roc", "roc is tried first");
    }
}

/// The frame's two phases recorded into the renderer's own encoder, with
/// its own (here empty) passes between them, give the lists `render` gives;
/// the late phase without the early one is refused.
#[test]
fn the_gpu_driven_phases_record_into_the_renderers_encoder() {
    let Some((device, queue)) = device("the_gpu_driven_phases_record_into_the_renderers_encoder") else { return };
    let (attachments, bounds) = one_box();
    let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
    let depth = sampled_depth(&device, attachments.depth);
    let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
    let forward = forward_camera();
    for method in GPU_METHODS {
        let mut culler = GpuCuller::new(&device, &queue, attachments, &bounds, &method.parse().unwrap(), draw).unwrap();
        let mut encoder = device.create_command_encoder(&Default::default());
        let refused = culler.encode_late(&mut encoder, &target);
        assert!(matches!(refused, Err(EmbedError::Sequence(_))), "{method}: {refused:?}");
        for expected in [[0, 1], [1, 0]] {
            let mut encoder = device.create_command_encoder(&Default::default());
            culler.encode_early(&mut encoder, &forward, &target).unwrap();
            // The renderer's own pass over the early list would go here; a
            // pass clearing the depth stands for it.
            let clear = wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            };
            drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                depth_stencil_attachment: Some(clear),
                ..Default::default()
            }));
            culler.encode_late(&mut encoder, &target).unwrap();
            queue.submit([encoder.finish()]);
            assert_eq!(culler.read_counts().unwrap(), expected, "{method}");
        }
    }
}

/// `roc` and `ioc` on a device opened without `SHADER_EARLY_DEPTH_TEST`
/// (as wgpu opens one by default) are refused, naming the feature; `hiz`,
/// which needs no feature, runs there.
#[test]
fn box_tests_are_refused_on_a_device_without_forced_early_depth_tests() {
    if device("box_tests_are_refused_on_a_device_without_forced_early_depth_tests").is_none() {
        return;
    }
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).unwrap();
    let (device, queue) = pollster::block_on(adapter.request_device(&Default::default())).unwrap();
    assert!(!device.features().contains(RASTER_FEATURES));
    let (attachments, bounds) = one_box();
    let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
    let new = |method: &str| GpuCuller::new(&device, &queue, attachments, &bounds, &method.parse().unwrap(), draw);
    for method in ["roc", "ioc"] {
        match new(method).err() {
            Some(EmbedError::Adapter(message)) => assert!(message.contains("SHADER_EARLY_DEPTH_TEST"), "{message}"),
            other => panic!("{method} without the feature: {other:?}"),
        }
    }
    assert!(new("hiz").is_ok());
}

/// A depth-only pipeline reading a uniform at group 0, binding 0 (a scale,
/// all ones) and a visible list at group 1, binding 0, drawing instance 0
/// of a list as one triangle over the whole target at depth 0 (its first
/// three vertices; the others degenerate).
fn list_pipeline(device: &wgpu::Device, depth_format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var<uniform> scale: vec4<f32>;
             struct VisibleList { count: u32, capacity: u32, ids: array<u32> }
             @group(1) @binding(0) var<storage, read> visible: VisibleList;
             @vertex
             fn vs(@builtin(instance_index) k: u32, @builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
                 if visible.ids[k] != 0u || v >= 3u {
                     return vec4<f32>(0.0);
                 }
                 let corner = vec2<f32>(f32((v << 1u) & 2u), f32(v & 2u)) * 2.0 - 1.0;
                 return scale * vec4<f32>(corner, 0.0, 1.0);
             }"
            .into(),
        ),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: None,
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: depth_format,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}
