//! Tests over all scenes: generation, budgets, determinism, walkthrough
//! clearance and errors; and the motion of the scenes that move by
//! themselves.

use super::*;
use glam::Vec3;
use occlude_core::{Aabb, Camera, Sampling, Scene};
use std::collections::BTreeSet;
use std::time::Instant;

/// The most triangles a `small` scene may have (the tests render them).
const SMALL_TRIANGLES: usize = 200_000;
/// The most instances a `small` scene may have.
const SMALL_INSTANCES: usize = 5_000;

fn small(name: &str, seed: u64) -> Scene {
    generate(name, Size::Small, seed).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn small_scenes_generate_valid_within_budget_with_a_walkthrough() {
    for name in SCENE_NAMES {
        let s = small(name, 1);
        assert_eq!(s.name, name);
        assert_eq!(s.validate(), Ok(()));
        assert!(s.triangle_count() <= SMALL_TRIANGLES, "{name}: {} triangles", s.triangle_count());
        assert!(s.triangle_count() >= SMALL_TRIANGLES / 5, "{name}: only {} triangles", s.triangle_count());
        assert!(s.instances.len() <= SMALL_INSTANCES, "{name}: {} instances", s.instances.len());
        assert!(s.instances.len() >= 300, "{name}: only {} instances", s.instances.len());
        assert!(s.path.keyframes.len() >= 2, "{name}: path has {} keyframes", s.path.keyframes.len());
        // The CHC paper's city and plant walkthroughs run past its frames
        // 1800 and 3800 (below); the others last 20-45 s.
        let d = s.path.duration();
        assert!((20.0..=135.0).contains(&d), "{name}: walkthrough lasts {d} s");
        assert!(s.path.keyframes.windows(2).all(|k| k[1].time > k[0].time), "{name}: key times must increase");
        // Instancing: far fewer unique triangles than drawn ones.
        assert!(s.unique_triangle_count() * 4 < s.triangle_count(), "{name}: little instancing");
        // Materials spread over several ids, each of them used.
        let used: BTreeSet<u32> = s.instances.iter().map(|i| i.material).collect();
        assert!((4..=16).contains(&s.material_count), "{name}: {} materials", s.material_count);
        assert_eq!(used.len() as u32, s.material_count, "{name}: unused material ids");
    }
}

#[test]
fn generation_is_deterministic_and_depends_on_the_seed() {
    for name in SCENE_NAMES {
        let (a, b, c) = (small(name, 7), small(name, 7), small(name, 8));
        let transforms = |s: &Scene| s.instances.iter().map(|i| (i.mesh, i.material, i.transform)).collect::<Vec<_>>();
        assert_eq!(transforms(&a), transforms(&b), "{name}: same seed, different instances");
        assert_eq!(a.triangle_count(), b.triangle_count());
        assert_eq!(a.unique_triangle_count(), b.unique_triangle_count());
        assert_eq!(a.path, b.path, "{name}: same seed, different path");
        assert_ne!(transforms(&a), transforms(&c), "{name}: the seed changes nothing");
    }
}

/// Panics unless every keyframe and 1500 sampled eye positions of the
/// walkthrough are at least 0.5 m from every instance's box (the near plane
/// is 0.1 m: the camera must never be inside or against an object).
fn assert_walkthrough_clear(s: &Scene) {
    let mut eyes: Vec<Vec3> = s.path.keyframes.iter().map(|k| k.position).collect();
    eyes.extend(s.path.sample(1500, 1.0, 0.1, 1.0).iter().map(|c| c.position));
    assert_eyes_clear(s, &eyes);
}

/// Panics unless every one of `eyes` is at least 0.5 m from every
/// instance's box.
fn assert_eyes_clear(s: &Scene, eyes: &[Vec3]) {
    for (e, eye) in eyes.iter().enumerate() {
        for (i, inst) in s.instances.iter().enumerate() {
            let d = inst.bounds.distance_squared(*eye).sqrt();
            assert!(d >= 0.5, "{}: eye {e} at {eye} is {d:.2} m from instance {i} {:?}", s.name, inst.bounds);
        }
    }
}

#[test]
fn walkthroughs_keep_clear_of_every_object() {
    for name in SCENE_NAMES.into_iter().filter(|name| !MOVING_SCENES.contains(name)) {
        assert_walkthrough_clear(&small(name, 3));
    }
}

#[test]
fn walkthroughs_look_at_the_scene() {
    // Every key looks somewhere (target away from the eye), and most of the
    // walkthrough is near or inside the scene.
    for name in SCENE_NAMES {
        let s = small(name, 1);
        let b = s.bounds();
        for k in &s.path.keyframes {
            assert!((k.target - k.position).length() > 1.0, "{name}: key at {} looks at itself", k.time);
        }
        let inside = s.path.keyframes.iter().filter(|k| b.contains_point(k.position)).count();
        assert!(inside * 2 >= s.path.keyframes.len(), "{name}: only {inside} keys inside the scene's box");
    }
}

/// The walkthrough's cameras as `occlude bench` renders them by default:
/// 30 frames per second over the whole path, 1024 x 768, near plane 0.25 m,
/// far plane the scene's view distance or 1.5 times its diagonal
/// (`bench::runner::far_plane`).
fn bench_cameras(s: &Scene) -> Vec<Camera> {
    let far = s.view_distance.unwrap_or(s.bounds().extent().length() * 1.5);
    s.path.sample_with(Sampling::Rate { fps: 30.0, limit: None }, 1024.0 / 768.0, 0.25, far)
}

/// Share of the scene's triangles in instances whose boxes meet the camera's
/// view frustum: what view-frustum culling draws, counted per instance (the
/// CHC paper's VFC row divided by its scene's triangles).
fn frustum_share(s: &Scene, camera: &Camera) -> f64 {
    let frustum = camera.frustum();
    let drawn: u64 = (0..s.instances.len())
        .filter(|&i| frustum.intersects(&s.instances[i].bounds))
        .map(|i| s.instance_triangles(i))
        .sum();
    drawn as f64 / s.triangle_count() as f64
}

/// [`frustum_share`] of every camera.
fn frustum_shares(s: &Scene, cameras: &[Camera]) -> Vec<f64> {
    cameras.iter().map(|c| frustum_share(s, c)).collect()
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// The CHC paper's teapot walkthrough has VFC draw 11,139,928 of the
/// scene's 11,520,000 triangles a frame on average (Table 1): the long
/// field stays in view, seen from outside. Ours keeps at least 92 % of the
/// field's triangles in the frustum on average (within 5 points of the
/// published 96.7 %), never enters the field's box and keeps clear of the
/// ground, at every size (the teapots share their meshes: even `paper`
/// builds in a moment).
#[test]
fn the_teapot_walkthrough_keeps_the_field_in_view_from_outside() {
    for size in Size::ALL {
        let s = generate("teapots", size, 1).unwrap();
        let cameras = bench_cameras(&s);
        let share = mean(&frustum_shares(&s, &cameras));
        assert!(share >= 0.92, "teapots {size}: {:.1} % of the triangles in view on average", 100.0 * share);
        let field = s.instances[1..].iter().fold(Aabb::EMPTY, |b, i| b.union(&i.bounds));
        for camera in &cameras {
            assert!(!field.contains_point(camera.position), "teapots {size}: eye {} inside the field", camera.position);
        }
        assert_walkthrough_clear(&s);
    }
}

/// The eye positions of the walkthrough at 30 frames per second.
fn eyes_at_30_fps(s: &Scene) -> Vec<Vec3> {
    bench_cameras(s).iter().map(|c| c.position).collect()
}

/// The CHC paper's city walkthrough runs past frame 1800, with the view
/// "elevated above the roofs" over frames 1200-1800 and a spike "around
/// frame 1600". Ours, at every size: at least 1,800 frames at 30 fps, a
/// street walk at eye height for the first 10 s (the default `occlude bench`
/// frames), above every object from frame 1210 to 1800, at its highest
/// between frames 1560 and 1650, and clear of every object (every frame
/// at 30 fps is checked: the path is long). `downtown`, the same streets
/// over more blocks, walks the same path.
#[test]
fn the_city_walkthrough_rises_above_the_roofs_where_the_papers_does() {
    for (name, size) in ["city", "downtown"].into_iter().flat_map(|n| Size::ALL.map(|size| (n, size))) {
        let s = generate(name, size, 1).unwrap();
        let eyes = eyes_at_30_fps(&s);
        assert!(eyes.len() >= 1800, "{name} {size}: {} frames", eyes.len());
        assert!(eyes[..300].iter().all(|e| (e.y - walk::EYE).abs() < 0.01), "{name} {size}: off the street");
        let roofs = s.instances.iter().map(|i| i.bounds.max.y).fold(f32::MIN, f32::max);
        for (f, e) in eyes.iter().enumerate().take(1801).skip(1210) {
            assert!(e.y > roofs, "{name} {size}: frame {f} at {e}, roofs at {roofs}");
        }
        let highest = (0..eyes.len()).max_by(|&a, &b| eyes[a].y.total_cmp(&eyes[b].y)).unwrap();
        assert!((1560..=1650).contains(&highest), "{name} {size}: highest at frame {highest}");
        assert_walkthrough_clear(&s);
        assert_eyes_clear(&s, &eyes);
    }
}

/// The CHC paper's power plant walkthrough runs past frame 3800, with views
/// "along the border of the model directed outwards" as short holes in its
/// Figure 7 and views "inside the power plant with high depth complexity"
/// near frames 3700-3800. Ours, at every size: at least 3,800 frames at 30
/// fps, the eye outside the hall's walls for at most 4 s at a time, the last
/// 600 frames on the ground floor inside the hall, and clear of every
/// object on every frame.
#[test]
fn the_plant_walkthrough_is_as_long_as_the_papers_and_stays_in_the_hall() {
    for size in Size::ALL {
        let s = generate("plant", size, 1).unwrap();
        let eyes = eyes_at_30_fps(&s);
        assert!(eyes.len() >= 3800, "plant {size}: {} frames", eyes.len());
        let hall =
            s.instances.iter().filter(|i| i.material == plant::WALL).fold(Aabb::EMPTY, |b, i| b.union(&i.bounds));
        let mut outside = 0;
        for (f, e) in eyes.iter().enumerate() {
            outside = if hall.contains_point(*e) { 0 } else { outside + 1 };
            assert!(outside <= 120, "plant {size}: frame {f} at {e}, 4 s outside the hall {hall:?}");
        }
        for (f, e) in eyes.iter().enumerate().skip(eyes.len() - 600) {
            assert!(hall.contains_point(*e) && e.y < 3.0, "plant {size}: frame {f} at {e}, not on the ground floor");
        }
        assert_walkthrough_clear(&s);
        assert_eyes_clear(&s, &eyes);
    }
}

/// The CHC Table 1 inputs change only what they say, at every size: the
/// same meshes; the teapots' and the plant's instances unchanged, the
/// city's but for the lots its lower flight passes through (at most 2 %);
/// every walkthrough clear of every object on every frame at 30 fps; the
/// teapots' 871 frames from outside the field, most of it in view; the
/// city's flight, lower than occlude's own, still 20 m above the street
/// over frames 1210-1800 and at its highest around frame 1600; the plant's
/// eye where occlude's own is, with a narrower view that reaches less far.
#[test]
fn the_chc_table1_inputs_change_only_the_walkthroughs_and_views() {
    for size in Size::ALL {
        for name in ["teapots", "city", "plant"] {
            let own = generate(name, size, 1).unwrap();
            let s = generate_with(name, size, 1, Inputs::ChcTable1).unwrap();
            assert_eq!(s.meshes.len(), own.meshes.len(), "{name} {size}");
            // The instances are occlude's own, in the same order, some left out.
            let mut own_left = own.instances.iter();
            for i in &s.instances {
                let found = own_left.any(|o| (o.mesh, o.transform, o.material) == (i.mesh, i.transform, i.material));
                assert!(found, "{name} {size}: an instance not in occlude's own scene");
            }
            let removed = own.instances.len() - s.instances.len();
            assert!(removed * 50 <= own.instances.len(), "{name} {size}: {removed} instances removed");
            if name != "city" {
                assert_eq!(removed, 0, "{name} {size}");
            }
            let eyes = eyes_at_30_fps(&s);
            assert_walkthrough_clear(&s);
            assert_eyes_clear(&s, &eyes);
            match name {
                "teapots" => {
                    assert_eq!(eyes.len(), 871, "teapots {size}");
                    let share = mean(&frustum_shares(&s, &bench_cameras(&s)));
                    assert!(share >= 0.92, "teapots {size}: {:.1} % in view", 100.0 * share);
                    let field = s.instances[1..].iter().fold(Aabb::EMPTY, |b, i| b.union(&i.bounds));
                    assert!(eyes.iter().all(|e| !field.contains_point(*e)), "teapots {size}: eye inside the field");
                }
                "city" => {
                    for (f, e) in eyes.iter().enumerate().take(1801).skip(1210) {
                        assert!(e.y > 20.0, "city {size}: frame {f} at {e}, not above the street");
                    }
                    let highest = (0..eyes.len()).max_by(|&a, &b| eyes[a].y.total_cmp(&eyes[b].y)).unwrap();
                    assert!((1560..=1650).contains(&highest), "city {size}: highest at frame {highest}");
                }
                _ => {
                    assert_eq!(eyes, eyes_at_30_fps(&own), "plant {size}");
                    assert!(s.path.keyframes.iter().all(|k| k.fov_y_deg < walk::FOV_Y_DEG), "plant {size}");
                    assert!(s.view_distance.unwrap() < own.bounds().extent().length(), "plant {size}");
                }
            }
        }
    }
}

/// Prints, for the CHC paper's scenes at every size, the mean share of
/// their triangles in the view frustum over the walkthrough (30 fps) and the
/// same per second of walkthrough, with occlude's own inputs and with the
/// CHC Table 1 ones: `cargo test -p occlude-scenes --release --
/// --ignored --nocapture frustum_shares`. The paper's VFC row gives the
/// share of its walkthroughs: teapots 96.7 %, city 15.1 %, plant 12.2 %.
#[test]
#[ignore = "generates the paper sizes (tens of millions of triangles); run by hand"]
fn frustum_shares_of_the_walkthroughs() {
    for (name, inputs) in
        ["teapots", "city", "plant"].into_iter().flat_map(|n| [(n, Inputs::Own), (n, Inputs::ChcTable1)])
    {
        for size in Size::ALL {
            let s = generate_with(name, size, 1, inputs).unwrap();
            let shares = frustum_shares(&s, &bench_cameras(&s));
            let seconds: Vec<String> = shares.chunks(30).map(|c| format!("{:.0}", 100.0 * mean(c))).collect();
            println!(
                "{name} {size} {inputs:?}: {} triangles, {} frames, mean {:.1} % in view; per second: {}",
                s.triangle_count(),
                shares.len(),
                100.0 * mean(&shares),
                seconds.join(" ")
            );
        }
    }
}

#[test]
fn the_paper_scenes_come_first_then_swarm_then_the_moving_scenes() {
    assert_eq!(SCENE_NAMES[..PAPER_SCENES.len()], PAPER_SCENES);
    assert_eq!(SCENE_NAMES[PAPER_SCENES.len()], "swarm");
    assert_eq!(SCENE_NAMES[PAPER_SCENES.len() + 1..], MOVING_SCENES);
    for name in SCENE_NAMES {
        let moves = generate_moving(name, Size::Small, 1).unwrap().1.is_some();
        assert_eq!(moves, MOVING_SCENES.contains(&name), "{name}");
    }
}

#[test]
fn sizes_parse_and_print() {
    for size in Size::ALL {
        assert_eq!(size.to_string().parse::<Size>().unwrap(), size);
    }
    assert_eq!("paper".parse::<Size>().unwrap(), Size::Paper);
    let e = "huge".parse::<Size>().unwrap_err();
    assert!(matches!(e, GenerateError::UnknownSize(ref s) if s == "huge"));
    let message = e.to_string();
    assert!(message.contains("huge") && message.contains("small, medium, paper"), "{message}");
}

#[test]
fn unknown_scene_names_the_valid_ones() {
    let e = generate("castle", Size::Small, 1).unwrap_err();
    assert!(matches!(e, GenerateError::UnknownScene(ref s) if s == "castle"));
    let message = e.to_string();
    assert!(message.contains("castle"));
    for name in SCENE_NAMES {
        assert!(message.contains(name), "{message} does not list {name}");
    }
}

#[test]
fn larger_sizes_plan_the_papers_counts() {
    // Without building the scenes: the teapot field, the city and downtown
    // (from a sample of their building meshes) and the figures.
    let (teapots, triangles) = teapots::planned_counts(Size::Paper);
    assert_eq!(teapots, 5000);
    assert!((10_500_000..=12_500_000).contains(&triangles), "paper teapots: {triangles} triangles");
    let (teapots, triangles) = teapots::planned_counts(Size::Medium);
    assert!(teapots > 1000 && (1_000_000..=3_000_000).contains(&triangles), "{teapots} teapots, {triangles}");
    let (figures, triangles) = figures::planned_counts(Size::Paper);
    assert!(figures > 72_000 && triangles > 5_000_000, "paper figures: {figures}, {triangles} triangles");
    let (instances, triangles) = city::planned_counts(city::layout(Size::Paper));
    assert!(instances > 5_000 && (700_000..=1_500_000).contains(&triangles), "paper city: {instances}, {triangles}");
    // The IOC poster's downtown: 31,392 objects.
    let (instances, _) = city::planned_counts(city::downtown_layout(Size::Paper));
    assert!((29_000..=34_000).contains(&instances), "paper downtown: {instances} objects");
    // The poster's rooms: 2,753 objects (cheap enough to build).
    let rooms = generate("rooms", Size::Paper, 1).unwrap().instances.len();
    assert!((2_500..=3_300).contains(&rooms), "paper rooms: {rooms} objects");
    let (figures, triangles) = figures::planned_counts(Size::Medium);
    assert!(figures > 10_000 && (1_000_000..=3_000_000).contains(&triangles), "{figures} figures, {triangles}");
}

/// Generates every scene at every size and prints a table of counts and
/// generation times (`cargo test -p occlude-scenes --release -- --ignored
/// --nocapture counts`).
#[test]
#[ignore = "generates the paper sizes (tens of millions of triangles); run by hand"]
fn counts_of_every_scene_and_size() {
    println!("| scene | size | triangles | instances | unique triangles | meshes | materials | path s | gen s |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for name in SCENE_NAMES {
        for size in Size::ALL {
            let start = Instant::now();
            let s = generate(name, size, 1).unwrap();
            let seconds = start.elapsed().as_secs_f64();
            println!(
                "| {name} | {size} | {} | {} | {} | {} | {} | {:.0} | {seconds:.2} |",
                s.triangle_count(),
                s.instances.len(),
                s.unique_triangle_count(),
                s.meshes.len(),
                s.material_count,
                s.path.duration()
            );
            if size != Size::Small {
                assert!(s.triangle_count() >= 400_000, "{name} {size}: {} triangles", s.triangle_count());
            }
            if MOVING_SCENES.contains(&name) {
                let (s, motion) = generate_moving(name, size, 1).unwrap();
                assert_walkthrough_clear_in_motion(&s, &motion.unwrap());
            } else {
                assert_walkthrough_clear(&s);
            }
        }
    }
}

fn small_moving(name: &str, seed: u64) -> (Scene, SceneMotion) {
    let (scene, motion) = generate_moving(name, Size::Small, seed).unwrap_or_else(|e| panic!("{name}: {e}"));
    (scene, motion.unwrap_or_else(|| panic!("{name} does not move")))
}

/// Panics unless, at every frame of `occlude bench` at 30 frames per
/// second, the eye is at least 0.5 m from every shown instance's box as
/// the scene is then.
fn assert_walkthrough_clear_in_motion(s: &Scene, motion: &SceneMotion) {
    let mut moving = s.clone();
    for t in s.path.frame_times(Sampling::Rate { fps: 30.0, limit: None }) {
        moving.apply(&motion.changes_at(t)).unwrap();
        let eye = s.path.at(t).unwrap().position;
        for (i, inst) in moving.instances.iter().enumerate().filter(|(_, inst)| inst.enabled) {
            let d = inst.bounds.distance_squared(eye).sqrt();
            assert!(d >= 0.5, "{}: eye at {t} s at {eye} is {d:.2} m from instance {i} {:?}", s.name, inst.bounds);
        }
    }
}

/// The moved instances' boxes and whether they are shown, every half
/// second of the first minute.
fn moved_boxes(s: &Scene, motion: &SceneMotion) -> Vec<(u32, Aabb, bool)> {
    let mut moving = s.clone();
    let moved: Vec<u32> = motion.moved().collect();
    (0..120)
        .flat_map(|k| {
            moving.apply(&motion.changes_at(k as f32 * 0.5)).unwrap();
            moved
                .iter()
                .map(|&i| (i, moving.instances[i as usize].bounds, moving.instances[i as usize].enabled))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn moving_scenes_move_deterministically_and_start_as_generated() {
    for name in MOVING_SCENES {
        let ((a, ma), (b, mb), (_, mc)) = (small_moving(name, 7), small_moving(name, 7), small_moving(name, 8));
        for t in [0.0, 1.5, 17.25] {
            assert_eq!(ma.changes_at(t), mb.changes_at(t), "{name}: same seed, different motion at {t} s");
            assert_ne!(ma.changes_at(t), mc.changes_at(t), "{name}: the seed changes no motion at {t} s");
        }
        // The scene as generated is the scene at time 0.
        let mut at_zero = a.clone();
        at_zero.apply(&ma.changes_at(0.0)).unwrap();
        let state = |s: &Scene| s.instances.iter().map(|i| (i.transform, i.enabled)).collect::<Vec<_>>();
        assert_eq!(state(&at_zero), state(&a), "{name}");
        assert_eq!(state(&a), state(&b), "{name}");
        assert_eq!(generate(name, Size::Small, 7).unwrap().instances.len(), a.instances.len());
    }
}

#[test]
fn moving_walkthroughs_keep_clear_of_every_shown_instance_at_every_frame() {
    for name in MOVING_SCENES {
        let (s, motion) = small_moving(name, 3);
        assert_walkthrough_clear_in_motion(&s, &motion);
    }
}

#[test]
fn traffic_is_the_city_with_cars_and_buses_driving_on_its_streets() {
    let (s, motion) = small_moving("traffic", 1);
    let city = small("city", 1);
    assert_eq!(s.path, city.path);
    assert_eq!(
        s.instances[..city.instances.len()].iter().map(|i| i.transform).collect::<Vec<_>>(),
        city.instances.iter().map(|i| i.transform).collect::<Vec<_>>()
    );
    let moved: Vec<u32> = motion.moved().collect();
    assert!(moved.iter().all(|&i| i as usize >= city.instances.len()), "a building moves");
    let tall = moved.iter().filter(|&&i| s.instances[i as usize].bounds.extent().y > 3.0).count();
    assert!(tall >= 20 && moved.len() - tall >= 150, "{tall} buses and trucks, {} cars", moved.len() - tall);
    // Every vehicle lies on the road, across a street's width; the roads
    // are the city's ground.
    let ground = city.instances[0].bounds;
    let on_road = |lo: f32, hi: f32| {
        let line = (0.5 * (lo + hi) / city::PITCH).round() * city::PITCH;
        lo >= line - 0.5 * city::STREET && hi <= line + 0.5 * city::STREET
    };
    for (i, b, shown) in moved_boxes(&s, &motion) {
        assert!(shown);
        assert!(
            b.min.x >= ground.min.x && b.max.x <= ground.max.x && b.min.z >= ground.min.z && b.max.z <= ground.max.z,
            "{i}: {b:?}"
        );
        assert!(on_road(b.min.x, b.max.x) || on_road(b.min.z, b.max.z), "vehicle {i} off the streets: {b:?}");
        assert!(b.min.y >= 0.0, "{i}: {b:?}");
    }
    // Cars drive 8-14 m/s, buses 6-10.
    let at = |t: f32| {
        let mut m = s.clone();
        m.apply(&motion.changes_at(t)).unwrap();
        m
    };
    let (before, after) = (at(1.0), at(1.5));
    for &i in &moved {
        let d = before.instances[i as usize].bounds.center().distance(after.instances[i as usize].bounds.center());
        assert!((3.0..=7.0).contains(&d) || d > 100.0, "vehicle {i} drove {d} m in 0.5 s");
    }
}

#[test]
fn crowd_is_the_rooms_with_people_inside_and_doors_that_open_and_close() {
    let (s, motion) = small_moving("crowd", 1);
    let rooms = small("rooms", 1);
    assert_eq!(s.path, rooms.path);
    let building = rooms.bounds();
    let moved: Vec<u32> = motion.moved().collect();
    let boxes = moved_boxes(&s, &motion);
    let doors: BTreeSet<u32> = boxes.iter().filter(|(_, _, shown)| !shown).map(|&(i, _, _)| i).collect();
    let people = moved.len() - doors.len();
    assert!(people >= 20 && doors.len() >= 3, "{people} people, {} doors", doors.len());
    for &door in &doors {
        let shown: BTreeSet<bool> = boxes.iter().filter(|(i, _, _)| *i == door).map(|&(_, _, shown)| shown).collect();
        assert_eq!(shown.len(), 2, "door {door} never closes");
    }
    for (i, b, _) in boxes {
        assert!(building.contains_point(b.min) && building.contains_point(b.max), "{i}: {b:?} outside {building:?}");
        assert!(b.min.y >= 0.0 && b.max.y <= 2.1, "{i}: {b:?} not on the ground floor");
    }
}
