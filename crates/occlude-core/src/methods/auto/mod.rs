//! `auto`: occlusion culling that pays for itself, choosing per frame among
//! raster occlusion culling (`roc`, where the backend has GPU-resident
//! culling), two-phase Hi-Z (`hiz`, where it also has depth pyramids),
//! CHC++ (`chcpp`) and view-frustum culling (`vfc`) by what each has been
//! measured to cost.
//!
//! **What it decides.** Which one method renders the frame. Each is
//! conservative, so every frame's image is `vfc`'s whichever runs; the
//! choice changes only the time.
//!
//! **On what evidence.** The frame time the backend reports after each
//! frame ([`CullingMethod::finish_frame`]): measured on a GPU, simulated on
//! the soft backend. A backend that reports none (a renderer's own) is
//! charged by [`CostModel`] from the frame's draw and query counts, as
//! NOHC decides per node from a cost model (CHC++ paper, section 3.2, after
//! Guthe et al. 2006); `auto` says so once.
//!
//! **How.** The method in use is the current one; its frames keep a running
//! mean. Another method is tried now and then for a probe: one frame to
//! warm up its temporal state (two for `hiz` and `roc` from nothing: their
//! second frame draws early all that the first found against no depth),
//! then two measured frames (a method's first frame after another ran is
//! not measured, the current one's included, unless it starts from exactly
//! the instances the one before found visible: below); `vfc`, which carries
//! no state, is probed by one measured frame. A probe ends as soon as it
//! cannot win even if its frames to come cost their lower bound (below;
//! none where the backend models no costs). A method that would start from
//! another's visibility is tried before one that would start from nothing,
//! its try being the shorter. If the probe's mean beats the current mean by
//! `auto.margin` (5 %), the probed method becomes current; `vfc` becomes
//! current unless the current mean beats it by the margin, so occlusion
//! culling runs only while it pays for itself by the margin. The next probe
//! of a method waits long enough for all probes together to cost at most
//! `auto.budget` (1 %) of the frame time, each method an equal share: a
//! method measured at three times the current one's time waits far longer
//! than one within a few percent. The wait also doubles with each lost
//! probe, from `auto.probe` frames (32). Where the backend models its costs
//! ([`Backend::cost_model`]), each choice's frames have lower bounds:
//! `vfc`'s draws of the instances in view, walked until they show that
//! `vfc` cannot take over; the fixed passes of `roc` and `hiz` (dispatches,
//! a depth pyramid); `chcpp`'s wait for its first query when it starts from
//! nothing ([`CullingMethod::floor_ms`]). The frame that pays for finding a
//! bound (`vfc`'s walk) measures no choice. The first frame runs the choice
//! whose frame from nothing costs least at best; a probe whose bound cannot
//! beat the current mean by the margin is spared; a first try whose warm-up
//! must cost more than the current mean waits until the budget covers that
//! much. On a scene drawn in microseconds, no method whose fixed passes
//! take longer is ever tried. A method is tried at once, whatever its wait,
//! when the current method's mean grows past that method's last measured
//! time by the margin: a change of view that makes the current method stop
//! paying is found without waiting.
//!
//! A method that `auto` switches to starts from what the method before
//! found visible in the frame before ([`CullingMethod::seed`]), as CHC++
//! starts each frame from the last one's classification (section 3.1):
//! `roc` and `hiz` draw it first, `chcpp` takes it as its classification
//! (its own set, by leaf, is coarser: a method seeded from it warms up a
//! frame). A GPU-driven method's set is copied on the device to another,
//! and read back for `chcpp`, which the switching frame pays for. `vfc`
//! gives none: a method switched to from `vfc` starts from what it knew.
//! After a rebuild of the hierarchy (other node ids) every method starts
//! anew. The rules are [`Chooser`]'s, which the wgpu embedding's
//! `GpuCuller` shares.
//!
//! **What it costs.** The first frames try once each method that might win
//! (without a cost model, every method, the GPU-driven ones first, the
//! cheapest to try on a current GPU); after that, probes cost about
//! `auto.budget` of the time. The choice assumes that
//! neighbouring frames cost about the same (a camera that moves smoothly).

use super::chcpp::ChcppParams;
use super::options::{MethodParams, OptionError, ParamVisitor};
use super::tracked::Tracked;
use super::{CullingMethod, FrameContext, Method};
use crate::backend::Backend;
use crate::cost_model::CostModel;
use crate::hierarchy::Since;
use crate::stats::FrameStats;
use std::ops::ControlFlow;

mod chooser;

pub use chooser::{Bound, Chooser, Ticket};

/// Parameters of `auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoParams {
    /// `auto.probe`: the shortest wait, in frames, before a method other
    /// than the current one is tried again; doubled after each probe it
    /// loses.
    pub probe: u32,
    /// `auto.margin`: how much faster than the current method a probed one
    /// must be to take over (0.05: 5 %), so that noise does not flip the
    /// choice back and forth; and how much faster than `vfc` a method must
    /// be to keep running.
    pub margin: f32,
    /// `auto.budget`: the share of the frame time probes may cost on
    /// average (0.01: 1 %).
    pub budget: f32,
    /// `auto.gpu`: whether `roc` and `hiz` are among the choices where the
    /// backend runs them.
    pub gpu: bool,
}

impl Default for AutoParams {
    fn default() -> Self {
        Self { probe: 32, margin: 0.05, budget: 0.01, gpu: true }
    }
}

impl MethodParams for AutoParams {
    const METHOD: &'static str = "auto";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("probe", &mut self.probe, "an integer from 4 to 100000 (frames)", |p| (4..=100_000).contains(p))?;
        v.value("margin", &mut self.margin, "a number from 0 to 0.5", |m| (0.0..=0.5).contains(m))?;
        v.value("budget", &mut self.budget, "a number from 0.001 to 1", |b| (0.001..=1.0).contains(b))?;
        v.flag("gpu", &mut self.gpu)
    }
}

/// `auto`: the method that pays for itself (module documentation).
///
/// **Use it** when you do not know whether occlusion culling pays on your
/// scenes: on a scene with little occlusion, or geometry your GPU draws in
/// a fraction of a millisecond, it settles on frustum culling.
///
/// **Cost.** Its first frames try each method that might win once (about
/// ten frames, some of them slower than frustum culling: the first method
/// starts from nothing and tests everything, the later ones from what the
/// one before found visible); where the backend models its costs, a method
/// whose fixed passes alone outlast the running method's frame is not
/// tried. After that, probes cost about `auto.budget` (1 %) of the
/// frame time. Memory: the state of every method it may choose.
///
/// **Requirements.** Frame times from the backend
/// ([`FrameStats::frame_ms`]); without them the backend's cost model, or
/// [`CostModel::default`], charges the frames from their counts, less
/// faithfully. `roc` and `hiz` are among the choices only where the
/// backend has GPU-resident culling (and depth pyramids, for `hiz`).
///
/// **Limits.** It chooses among four methods (not `om`, `ioc`, `chc`); it
/// assumes that neighbouring frames cost about the same, so after a cut
/// to another view it may run the wrong method until the next probe; in
/// the embedding's `Culler` its choices are `chcpp` and `vfc` (its
/// `GpuCuller` runs `auto` among `roc`, `hiz` and `vfc` by the same
/// [`Chooser`]).
pub struct Auto {
    params: AutoParams,
    /// The methods it chooses among; empty until the first frame, when the
    /// backend is known.
    methods: Vec<Box<dyn CullingMethod + Send>>,
    /// What each was built from, to build it anew.
    kinds: Vec<Method>,
    /// The hierarchy the methods' state is for.
    tracked: Tracked,
    /// Which of them runs each frame; made with them.
    chooser: Option<Chooser>,
    /// The frame under way: the method running it.
    ticket: Option<Ticket>,
    /// The backend's own cost model (a simulator's), if it has one: it
    /// charges frames the backend reports no time for (else the default
    /// model), and bounds `vfc`'s time.
    model: Option<CostModel>,
    /// Nodes the estimate of `vfc`'s time visited in `prepare`, charged to
    /// the frame once it has begun.
    estimate_steps: u64,
    /// Whether the fallback was announced.
    warned: bool,
    warnings: Vec<String>,
}

impl Auto {
    /// `auto` with `params`, no frame seen yet.
    pub fn new(params: AutoParams) -> Self {
        Self {
            params,
            methods: Vec::new(),
            kinds: Vec::new(),
            tracked: Tracked::default(),
            chooser: None,
            ticket: None,
            model: None,
            estimate_steps: 0,
            warned: false,
            warnings: Vec::new(),
        }
    }

    /// The names of the methods `auto` chooses among, the first tried first
    /// (empty before the first frame).
    pub fn choices(&self) -> Vec<&'static str> {
        self.methods.iter().map(|m| m.name()).collect()
    }

    /// Makes the choices for `backend`: `roc` and `hiz` only where they run
    /// there. Where the backend models its costs, the first tried is the
    /// one whose frame from nothing costs least at best ([`bounds`]; ties
    /// in the order `roc`, `hiz`, `chcpp`, `vfc`).
    fn choose_among(&mut self, ctx: &FrameContext<'_>, backend: &mut dyn Backend) {
        let (culling, pyramids) = match backend.gpu_culling() {
            Ok(gpu) => (true, gpu.pyramid_support().is_ok()),
            Err(_) => (false, false),
        };
        let gpu = self.params.gpu;
        let roc = (gpu && culling).then(|| Method::Roc(Default::default()));
        let hiz = (gpu && pyramids).then(|| Method::Hiz(Default::default()));
        let mut methods: Vec<(Method, Box<dyn CullingMethod + Send>)> = roc
            .into_iter()
            .chain(hiz)
            .chain([Method::Chcpp(ChcppParams::default()), Method::Vfc])
            .map(|m| {
                let built = m.build().expect("default parameters are valid");
                (m, built)
            })
            .collect();
        self.model = backend.cost_model();
        if let Some(model) = self.model {
            let resolution = backend.resolution();
            let mut keyed = Vec::new();
            for (method, built) in methods {
                let (bound, steps) = bounds(built.as_ref(), ctx, &model, resolution, true, f64::INFINITY);
                self.estimate_steps += steps;
                keyed.push((bound.warm_up, (method, built)));
            }
            // A stable sort: ties keep the default order.
            keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
            methods = keyed.into_iter().map(|(_, m)| m).collect();
        }
        let cold: Vec<u64> = methods.iter().map(|(m, _)| cold_frames(m)).collect();
        let vfc = methods.iter().position(|(m, _)| *m == Method::Vfc);
        (self.kinds, self.methods) = methods.into_iter().unzip();
        let seeding: Vec<_> = self.methods.iter().map(|m| m.carried_visibility()).collect();
        self.chooser = Some(Chooser::new(self.params, &cold, vfc).with_seeding(&seeding));
    }

    /// The method running the frame under way (the first before any).
    fn running(&self) -> usize {
        self.ticket.map_or(0, |t| t.choice)
    }

    /// The frame's time in ms: the backend's, or modelled from its counts.
    fn frame_time(&mut self, stats: &FrameStats) -> f64 {
        if stats.frame_ms > 0.0 {
            return stats.frame_ms;
        }
        if !std::mem::replace(&mut self.warned, true) {
            self.warnings.push(
                "auto: the backend reports no frame time; frames are charged by its cost model \
                 (Backend::cost_model, else CostModel::default)"
                    .to_string(),
            );
        }
        let m = self.model.unwrap_or_default();
        let render = m.render_us(stats.draw_calls, stats.triangles, stats.fragments as f64);
        let queries = stats.queries as f64 * m.cpu_query_us + stats.query_boxes as f64 * m.gpu_query_box_us;
        (render + queries) * 1e-3
    }
}

/// Frames `method` runs from nothing before its frames cost what they will
/// (a [`Chooser`]'s warm-up): `roc`'s and `hiz`'s first frame has no depth
/// to test against, so their second draws all it found in its early list;
/// `chcpp`'s first queries every node, its second knows last frame's
/// visibility; `vfc` carries nothing. `auto` in the wgpu embedding's
/// `GpuCuller` warms its late tests up by it too.
pub fn cold_frames(method: &Method) -> u64 {
    match method {
        Method::Roc(_) | Method::Hiz(_) => 2,
        Method::Vfc => 0,
        _ => 1,
    }
}

/// Lower bounds of `method`'s frame times under `model` at `resolution`
/// ([`Bound`]): `vfc`'s from its draws ([`vfc_bound`]), the others' from
/// their fixed passes ([`CullingMethod::floor_ms`]), its warm-up's as from
/// nothing where it will not be seeded (`from_nothing`); and the nodes
/// `vfc`'s walk visited, to be charged to the frame. `vfc`'s walk stops
/// once its bound reaches `enough` ms.
fn bounds(
    method: &dyn CullingMethod,
    ctx: &FrameContext<'_>,
    model: &CostModel,
    resolution: (u32, u32),
    from_nothing: bool,
    enough: f64,
) -> (Bound, u64) {
    if method.name() == "vfc" {
        let (bound, steps) = vfc_bound(ctx, model, enough);
        return (Bound { measured: bound, warm_up: bound, costs_a_frame: steps > 0 }, steps);
    }
    let floor = |cold| method.floor_ms(ctx, model, resolution, cold);
    (Bound { measured: floor(false), warm_up: floor(from_nothing), costs_a_frame: false }, 0)
}

/// A lower bound of `vfc`'s frame time under `model`, ms: one draw call
/// for each shown instance in the leaves in view and its triangles
/// ([`CostModel::draws_floor_ms`]); and the nodes its walk visited, to be
/// charged as `vfc`'s walk is.
/// The walk stops once the bound reaches `enough` ms: part of the draws
/// bounds the whole from below too.
fn vfc_bound(ctx: &FrameContext<'_>, model: &CostModel, enough: f64) -> (f64, u64) {
    let h = ctx.hierarchy;
    let mut counted = vec![false; ctx.scene.instances.len()];
    let (mut draws, mut triangles) = (0u64, 0u64);
    let visited = ctx.walk_leaves_in_view(h.root(), |leaf| {
        for &i in h.instances(leaf) {
            let i = i as usize;
            if ctx.scene.instances[i].enabled && !std::mem::replace(&mut counted[i], true) {
                draws += 1;
                triangles += ctx.scene.instance_triangles(i);
            }
        }
        if model.draws_floor_ms(draws, triangles) >= enough {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    (model.draws_floor_ms(draws, triangles), visited)
}

impl CullingMethod for Auto {
    fn name(&self) -> &'static str {
        "auto"
    }

    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let rebuilt = matches!(self.tracked.since(ctx.hierarchy), Since::New);
        if self.methods.is_empty() {
            self.choose_among(ctx, backend);
        } else if rebuilt {
            // A method seeing a rebuilt tree would release every device
            // resource, the other methods' too: instead all are released
            // here and every method starts anew, making its own.
            if let Ok(gpu) = backend.gpu_culling() {
                gpu.release_all();
            }
            self.methods = self.kinds.iter().map(|m| m.build().expect("default parameters are valid")).collect();
        }
        let resolution = backend.resolution();
        let Self { methods, chooser, model, estimate_steps, params, .. } = self;
        let chooser = chooser.as_mut().expect("made above");
        // Where the backend models its costs, a due probe's frames cost at
        // least their bounds ([`bounds`]): a probe that cannot win is
        // spared, and with it frames of drawing everything in view where
        // occlusion culling wins by far, or of fixed passes dearer than a
        // whole frame of the method running. `vfc`'s walk stops at the
        // current mean over 1 - margin: past it, `vfc` cannot take over.
        let margin = f64::from(params.margin);
        let ticket = chooser.begin(|choice, mean, seeded| {
            let enough = mean / (1.0 - margin);
            let m = model.as_ref()?;
            let (bound, steps) = bounds(methods[choice].as_ref(), ctx, m, resolution, !seeded, enough);
            *estimate_steps += steps;
            Some(bound)
        });
        self.ticket = Some(ticket);
        self.methods[ticket.choice].prepare(ctx, backend);
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let steps = std::mem::take(&mut self.estimate_steps);
        if steps > 0 {
            backend.traverse(steps);
        }
        let running = self.running();
        if let Some(previous) = self.ticket.and_then(|t| t.seed_from()) {
            if let Some(visible) = self.methods[previous].visible_set(ctx) {
                self.methods[running].seed(ctx, backend, &visible);
            }
        }
        self.methods[running].render(ctx, backend);
    }

    fn finish_frame(&mut self, stats: &FrameStats) {
        let time = self.frame_time(stats);
        let running = self.running();
        self.methods[running].finish_frame(stats);
        if let (Some(chooser), Some(ticket)) = (&mut self.chooser, self.ticket) {
            chooser.record(ticket, time);
        }
    }

    fn take_warnings(&mut self) -> Vec<String> {
        let mut warnings = std::mem::take(&mut self.warnings);
        self.methods.iter_mut().for_each(|m| warnings.extend(m.take_warnings()));
        warnings
    }

    /// 1 for the method that rendered the frame (by its name), and
    /// `probe` 1 on a probe's frames.
    fn counters(&self) -> Vec<(&'static str, f64)> {
        let on = |yes: bool| f64::from(u8::from(yes));
        let running = self.running();
        let mut counters: Vec<_> = self.methods.iter().zip(0..).map(|(m, i)| (m.name(), on(i == running))).collect();
        counters.push(("probe", on(self.ticket.is_some_and(|t| t.is_probe()))));
        counters
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{culling_steps, drawn as drawn_by, method, queries, Rig, BEHIND, SIDE, WALL};
    use super::super::VisibleSet;
    use super::*;
    use crate::frame::render_frame;
    use crate::mock::Call;
    use crate::DrawnSet;

    /// Runs `auto` for `frames` frames on the wall rig (GPU culling on),
    /// each frame reported as costing `cost(frame, method)` ms; returns the
    /// method that rendered each frame.
    fn run(frames: u64, cost: impl Fn(u64, &str) -> f64) -> Vec<&'static str> {
        let (ran, choices) = run_modelled(None, frames, cost);
        assert_eq!(choices, ["roc", "hiz", "chcpp", "vfc"]);
        ran
    }

    /// [`run`] on a backend whose cost model is `model`, if any; also
    /// returns the choices in the order they were first tried.
    fn run_modelled(
        model: Option<CostModel>,
        frames: u64,
        cost: impl Fn(u64, &str) -> f64,
    ) -> (Vec<&'static str>, Vec<&'static str>) {
        let (ran, choices, _) = run_logged(model, frames, cost);
        (ran, choices)
    }

    /// [`run_modelled`], with each frame's calls to the backend.
    fn run_logged(
        model: Option<CostModel>,
        frames: u64,
        cost: impl Fn(u64, &str) -> f64,
    ) -> (Vec<&'static str>, Vec<&'static str>, Vec<Vec<Call>>) {
        let rig = Rig::wall();
        let mut backend = rig.mock().with_gpu_culling();
        backend.set_visible(BEHIND, false);
        if let Some(model) = model {
            backend = backend.with_cost_model(model);
        }
        let mut auto = Auto::new(AutoParams::default());
        let mut drawn = DrawnSet::default();
        let (mut ran, mut logs) = (Vec::new(), Vec::new());
        for frame in 0..frames {
            let mut ctx = FrameContext::new(&rig.scene, &rig.hierarchy, rig.camera, &mut drawn);
            auto.prepare(&mut ctx, &mut backend);
            backend.begin_frame(&rig.camera);
            auto.render(&mut ctx, &mut backend);
            backend.end_frame();
            let name = auto.counters().into_iter().find(|&(n, on)| on == 1.0 && n != "probe").unwrap().0;
            auto.finish_frame(&FrameStats { frame_ms: cost(frame, name), ..FrameStats::default() });
            ran.push(name);
            logs.push(backend.take_log());
        }
        (ran, auto.choices(), logs)
    }

    fn share(ran: &[&str], name: &str) -> f64 {
        ran.iter().filter(|&&n| n == name).count() as f64 / ran.len() as f64
    }

    #[test]
    fn the_fastest_method_takes_over_and_losing_probes_grow_rare() {
        let cost = |_, name: &str| match name {
            "vfc" => 1.0,
            "chcpp" => 0.5,
            _ => 2.0,
        };
        let ran = run(600, cost);
        // roc first (two frames from nothing, one measured), then probes of
        // hiz (from the instances roc found visible: two frames, both
        // measured), which loses, of chcpp (from hiz's), which takes over,
        // and of vfc (one frame, no state), which loses; chcpp, back from
        // vfc, warms up a frame.
        let start = ["roc", "roc", "roc", "hiz", "hiz", "chcpp", "chcpp", "vfc", "chcpp", "chcpp"];
        assert_eq!(ran[..10], start);
        assert!(share(&ran[10..], "chcpp") > 0.97, "{}", share(&ran[10..], "chcpp"));
        // Each probe of vfc costs 0.5 ms beyond chcpp's 0.5 ms: 1 % of the
        // time allows one in 100 frames.
        assert!(ran.iter().filter(|&&n| n == "vfc").count() <= 7);
        // roc and hiz, four times chcpp's time, wait past the 600 frames
        // once measured against chcpp (hiz, first measured against roc,
        // equally slow, is probed once more, from chcpp's set by leaf: a
        // warm-up frame and one measured frame, clearly slower, end that
        // probe).
        assert_eq!(ran.iter().filter(|&&n| n == "hiz").count(), 4);
        assert_eq!(ran.iter().filter(|&&n| n == "roc").count(), 3);
    }

    #[test]
    fn all_probes_together_stay_within_the_budget() {
        // vfc is fastest; each of the three others costs three times as
        // much, so every probe is pure loss.
        let cost = |_, name: &str| if name == "vfc" { 1.0 } else { 3.0 };
        let ran = run(6000, cost);
        let start = ran.iter().position(|&n| n == "vfc").unwrap() + 1;
        let excess: f64 = ran[start..].iter().map(|&n| cost(0, n) - 1.0).sum();
        let share = excess / (ran.len() - start) as f64;
        // The budget is 1 % of the time for all probes, not for each.
        assert!(share <= 0.0105, "probes cost {:.2} % of the frame time", share * 100.0);
        assert!(share > 0.0, "no method was probed again");
    }

    #[test]
    fn a_method_that_stops_paying_is_left_for_one_that_does() {
        // chcpp is fastest until frame 300, then twice vfc's time.
        let cost = |frame, name: &str| match (name, frame < 300) {
            ("vfc", _) => 1.0,
            ("chcpp", true) => 0.6,
            ("chcpp", false) => 2.0,
            _ => 3.0,
        };
        let ran = run(600, cost);
        assert!(share(&ran[100..300], "chcpp") > 0.9);
        assert!(share(&ran[400..], "vfc") > 0.9, "{}", share(&ran[400..], "vfc"));
    }

    #[test]
    fn a_method_at_the_margin_is_not_probed_frame_after_frame() {
        let run_at = |chcpp: f64| {
            run(600, move |_, name: &str| match name {
                "vfc" => 1.0,
                "chcpp" => chcpp,
                _ => 3.0,
            })
        };
        // chcpp beats vfc by just over the margin: it stays, and vfc is
        // probed at most once in 300 frames.
        let ran = run_at(0.949);
        assert!(share(&ran, "chcpp") > 0.97, "{}", share(&ran, "chcpp"));
        // By just under it, chcpp does not pay for itself: vfc runs, and
        // chcpp's probes stay rare.
        let ran = run_at(0.951);
        assert!(share(&ran[100..], "vfc") > 0.97, "{}", share(&ran[100..], "vfc"));
    }

    #[test]
    fn vfc_is_not_probed_where_the_cost_model_says_it_cannot_win() {
        let cost = |_, name: &str| if name == "vfc" { 1.0 } else { 0.5 };
        // One millisecond a draw call: drawing the wall rig's instances in
        // view costs far more than the 0.5 ms the others take.
        let slow_draws = CostModel { cpu_draw_call_us: 1000.0, ..CostModel::default() };
        let (ran, choices) = run_modelled(Some(slow_draws), 600, cost);
        assert_eq!(share(&ran, "vfc"), 0.0);
        assert_eq!(choices.last(), Some(&"vfc"), "tried last: its first frame is the dearest");
        // Under a model in which its draws are cheap, vfc is tried first
        // (and loses).
        let cheap_draws = CostModel { cpu_draw_call_us: 0.0, gpu_draw_call_us: 0.0, ..CostModel::default() };
        let (ran, choices) = run_modelled(Some(cheap_draws), 600, cost);
        assert_eq!((choices[0], ran[0]), ("vfc", "vfc"));
        assert!(share(&ran, "vfc") < 0.05);
    }

    #[test]
    fn a_method_whose_fixed_passes_outlast_vfcs_frame_is_never_tried() {
        // Draws nearly free: vfc's frame of 5 µs is shorter than roc's six
        // dispatches (18 µs), hiz's pyramid, and chcpp's first query from
        // nothing (30 µs). Were they tried, they would win; they are not.
        let cheap_draws =
            CostModel { cpu_draw_call_us: 0.01, gpu_draw_call_us: 0.01, gpu_triangle_ns: 0.0, ..CostModel::default() };
        let cost = |_, name: &str| if name == "vfc" { 0.005 } else { 0.0025 };
        let (ran, choices) = run_modelled(Some(cheap_draws), 600, cost);
        assert_eq!(choices[0], "vfc");
        assert!(ran.iter().all(|&m| m == "vfc"), "{:?}", ran.iter().find(|&&m| m != "vfc"));
        // Without a cost model every method is tried, and roc, first, wins.
        let (ran, _) = run_modelled(None, 600, cost);
        assert!(share(&ran, "vfc") < 0.05);
    }

    #[test]
    fn a_backend_without_frame_times_is_charged_by_the_cost_model_said_once() {
        let rig = Rig::wall();
        let mut backend = rig.mock();
        let mut auto = Auto::new(AutoParams::default());
        let mut drawn = DrawnSet::default();
        for _ in 0..5 {
            render_frame(&mut auto, &mut backend, &rig.scene, &rig.hierarchy, &rig.camera, &mut drawn);
        }
        let warnings = auto.take_warnings();
        assert_eq!(warnings.iter().filter(|w| w.contains("no frame time")).count(), 1, "{warnings:?}");
        // Without GPU-resident culling hiz is not among the choices.
        assert_eq!(auto.choices(), ["chcpp", "vfc"]);
        assert!(auto.chooser.as_ref().and_then(Chooser::mean).is_some_and(|m| m > 0.0));
    }

    #[test]
    fn a_method_switched_to_starts_from_what_the_one_before_found() {
        let cost = |_, name: &str| if name == "chcpp" { 0.5 } else { 1.0 };
        let (ran, _, logs) = run_logged(None, 12, cost);
        // roc from nothing draws nothing first; hiz, probed after it, draws
        // first what roc found visible, copied on the device: the wall and
        // the cube beside it, not the one behind.
        assert_eq!((ran[0], ran[3], ran[2]), ("roc", "hiz", "roc"));
        assert_eq!(culling_steps(&logs[0])[0], ("draw", vec![]));
        assert!(!logs[3].contains(&Call::ReadBack));
        assert_eq!(culling_steps(&logs[3])[0], ("draw", vec![WALL, SIDE]));
        // chcpp, probed after hiz, reads back what hiz found and starts
        // from it: it queries fewer nodes than from nothing.
        let first = ran.iter().position(|&m| m == "chcpp").unwrap();
        assert!(logs[first].contains(&Call::ReadBack));
        let rig = Rig::wall();
        let mut mock = rig.mock();
        mock.set_visible(BEHIND, false);
        let from_nothing = rig.run(&mut method("chcpp", &[]), &mut mock, 1).remove(0);
        assert!(
            queries(&logs[first]).len() < queries(&from_nothing).len(),
            "{} queries seeded, {} from nothing",
            queries(&logs[first]).len(),
            queries(&from_nothing).len()
        );
    }

    /// After a rebuild of the tree, the methods `auto` runs each make
    /// device resources of their own: a method seeing the rebuild alone
    /// would release the others' and leave them handles into its own.
    #[test]
    fn after_a_rebuild_each_method_makes_its_own_device_resources() {
        let (rig, rebuilt) = (Rig::wall(), Rig::wall().hierarchy);
        let mut backend = rig.mock().with_gpu_culling();
        backend.set_visible(BEHIND, false);
        let mut auto = Auto::new(AutoParams::default());
        let mut drawn = DrawnSet::default();
        let mut ran = Vec::new();
        for frame in 0..60 {
            // roc is fastest until the rebuild, hiz after it.
            let h = if frame < 20 { &rig.hierarchy } else { &rebuilt };
            let mut ctx = FrameContext::new(&rig.scene, h, rig.camera, &mut drawn);
            auto.prepare(&mut ctx, &mut backend);
            backend.begin_frame(&rig.camera);
            auto.render(&mut ctx, &mut backend);
            backend.end_frame();
            let drew = drawn_by(&backend.take_log());
            assert!(drew.contains(&WALL) && drew.contains(&SIDE), "frame {frame} drew {drew:?}");
            let name = auto.counters().into_iter().find(|&(n, on)| on == 1.0 && n != "probe").unwrap().0;
            let cost = match (name, frame < 20) {
                ("roc", true) | ("hiz", false) => 1.0,
                ("hiz", true) => 1.2,
                _ => 3.0,
            };
            auto.finish_frame(&FrameStats { frame_ms: cost, ..FrameStats::default() });
            ran.push((frame, name));
        }
        let ran_after = |m: &str| ran.iter().any(|&(f, n)| f >= 20 && n == m);
        assert!(ran_after("roc") && ran_after("hiz"), "{ran:?}");
        let ctx = FrameContext::new(&rig.scene, &rebuilt, rig.camera, &mut drawn);
        let flags: Vec<_> = auto.methods.iter().filter_map(|m| m.visible_set(&ctx)).collect();
        let device: Vec<_> = flags.iter().filter(|v| matches!(v, VisibleSet::Device(_))).collect();
        assert_eq!(device.len(), 2, "{flags:?}");
        assert_ne!(device[0], device[1], "roc and hiz hold the same flags");
    }

    #[test]
    fn the_walk_bounding_vfc_stops_once_the_bound_is_enough() {
        let rig = Rig::row(8);
        let mut drawn = DrawnSet::default();
        let ctx = FrameContext::new(&rig.scene, &rig.hierarchy, rig.camera, &mut drawn);
        let model = CostModel::default();
        let (whole, all_nodes) = vfc_bound(&ctx, &model, f64::INFINITY);
        assert!(whole > 0.0);
        let (part, some_nodes) = vfc_bound(&ctx, &model, whole / 4.0);
        assert!(part >= whole / 4.0 && part < whole, "{part} of {whole}");
        assert!(some_nodes < all_nodes, "{some_nodes} of {all_nodes} nodes");
    }
}
