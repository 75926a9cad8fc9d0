//! [`GpuCulling`] on the soft backend: the device's buffers are CPU vectors,
//! the compute passes loops over them, the box tests and list draws commands
//! of the exact rasterizer. Every command is charged on the simulated GPU
//! time line in order with the frame's draws and queries: a dispatch costs
//! `gpu_dispatch_us` plus `gpu_compute_item_ns` per element it touches, a
//! box test one instanced draw (`gpu_indirect_draw_us`) of boxes costing
//! `gpu_box_us` each (no per-query cost: there is no query),
//! `gpu_query_fragment_ns` per covered pixel (the depth test, as a query's)
//! and `gpu_box_fragment_ns` more per pixel that passes it (the fragment
//! shader writing the flag runs after the early depth test, only there), a
//! list draw `gpu_indirect_draw_us` per draw inside it plus
//! its triangles and fragments, a read-back `readback_us` after the GPU is
//! done. A depth pyramid is built by one dispatch per level past level 0,
//! each costing `gpu_pyramid_texel_ns` per texel it writes, and a box test
//! against it is one dispatch costing `gpu_hiz_box_ns` per box tested (not
//! near the eye, not outside the frustum) and `gpu_hiz_texel_ns` per texel
//! read. The CPU pays `cpu_dispatch_us` to record each dispatch or indirect
//! draw.
//!
//! Results are those of the wgpu backend's compute and raster passes: the
//! same padded box proxies, depth bias and near-region rule as the
//! CPU-driven queries (`occlude_core::query_box`), so a box is visible here
//! exactly when an occlusion query over it would count a pixel.

use super::{charge_gpu_time, GpuOp, SoftBackend};
use crate::raster::{CommandKind, DepthTest};
use occlude_core::depth_pyramid::box_footprint;
use occlude_core::{
    Aabb, BoxSet, ExpandInto, Flags, GpuCulling, GpuCullingUnsupported, IdList, ItemRange, Pyramid, RangeTable,
    RenderState,
};

impl SoftBackend {
    /// Charges a read-back: the frame waits until everything recorded so
    /// far has run and the copy has come back.
    fn read_back(&mut self) {
        self.flush();
        self.count.stats.readbacks += 1;
        let ready = self.clock.gpu_free + self.model.readback_us;
        self.clock.wait_until(ready);
    }

    /// Charges one compute dispatch over `items` elements, after everything
    /// recorded before it has run.
    fn dispatch(&mut self, items: usize) {
        self.dispatch_costing(self.model.compute_items_us(items as u64));
    }

    /// Charges one compute dispatch doing `work_us` of GPU work, after
    /// everything recorded before it has run.
    fn dispatch_costing(&mut self, work_us: f64) {
        self.flush();
        self.count.stats.dispatches += 1;
        self.clock.cpu_work(self.model.cpu_dispatch_us);
        self.culling_work(self.model.gpu_dispatch_us + work_us);
    }

    /// The box tests' common first step over the boxes of `boxes` named by
    /// `ids`: sets the flags of those touching the near region and returns
    /// the others inside the frustum, to be tested.
    fn boxes_to_test(&mut self, boxes: BoxSet, ids: IdList, flags: Flags) -> Vec<(u32, Aabb)> {
        let camera = self.camera.expect("a box test outside a frame");
        let frustum = camera.frustum();
        let mut rest = Vec::new();
        for &id in &self.device.lists[ids.0 as usize].ids {
            let Some(b) = self.device.boxes[boxes.0 as usize][id as usize] else { continue };
            if camera.box_touches_near_region(&b) {
                self.device.flags[flags.0 as usize][id as usize] = true;
            } else if frustum.intersects(&b) {
                rest.push((id, b));
            }
        }
        rest
    }

    /// Puts `us` of occlusion-test work on the GPU time line, issued now
    /// (everything recorded before it has run).
    fn culling_work(&mut self, us: f64) {
        self.clock.gpu_command(self.clock.cpu, us);
        charge_gpu_time(&mut self.count.stats, true, us);
    }

    /// Records an indirect multi-draw command: its CPU cost and its render
    /// state.
    fn indirect_draw(&mut self, state: RenderState) {
        let changed = self.count.indirect_draw(state);
        self.charge_state_change(changed);
        self.clock.cpu_work(self.model.cpu_dispatch_us);
    }
}

impl GpuCulling for SoftBackend {
    fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        self.device.create_boxes(boxes)
    }

    fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]) {
        self.device.update_boxes(boxes, changed);
    }

    fn release_all(&mut self) {
        self.device.release_all();
    }

    fn create_flags(&mut self, len: u32) -> Flags {
        self.device.create_flags(len)
    }

    fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        self.device.create_list(capacity, ids)
    }

    fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        self.device.create_table(ranges, items)
    }

    fn clear_flags(&mut self, flags: Flags) {
        let len = self.device.flags[flags.0 as usize].len();
        self.dispatch(len);
        self.device.flags[flags.0 as usize].fill(false);
    }

    /// Charged as GPU work over every slot, as a clear's dispatch is,
    /// without the dispatch.
    fn write_flags(&mut self, flags: Flags, set: &[bool]) {
        self.flush();
        let len = self.device.flags[flags.0 as usize].len();
        self.culling_work(self.model.compute_items_us(len as u64));
        self.device.write_flags(flags, set);
    }

    fn copy_flags(&mut self, src: Flags, dst: Flags) {
        let len = self.device.flags[dst.0 as usize].len();
        self.dispatch(len);
        self.device.copy_flags(src, dst);
    }

    fn test_boxes(&mut self, boxes: BoxSet, ids: IdList, flags: Flags) {
        let count = self.device.lists[ids.0 as usize].ids.len();
        self.dispatch(count);
        // The dispatch: near boxes are visible untested, boxes outside the
        // frustum hidden, the rest go to the raster list.
        let raster = self.boxes_to_test(boxes, ids, flags);
        // The indirect draw of the raster list, one box per instance.
        self.indirect_draw(RenderState::Query);
        self.culling_work(self.model.gpu_indirect_draw_us);
        self.count.stats.query_boxes += raster.len() as u64;
        for (_, b) in &raster {
            let first = self.triangles.len();
            self.push_box_triangles(b);
            let op = GpuOp {
                issued_us: self.clock.cpu,
                fixed_us: self.model.gpu_box_us,
                fragment_ns: self.model.gpu_query_fragment_ns,
                passed_ns: self.model.gpu_box_fragment_ns,
                query: None,
                cull: true,
            };
            self.record(CommandKind::Query(DepthTest::Less), first, true, op);
        }
        let results = self.run_recorded();
        let set = &mut self.device.flags[flags.0 as usize];
        for ((id, _), r) in raster.iter().zip(&results) {
            if r.passed > 0 {
                set[*id as usize] = true;
            }
        }
    }

    fn pyramid_support(&mut self) -> Result<(), GpuCullingUnsupported> {
        Ok(())
    }

    fn create_pyramid(&mut self) -> Pyramid {
        self.device.create_pyramid(self.depth.width(), self.depth.height())
    }

    fn build_pyramid(&mut self, pyramid: Pyramid) {
        self.flush();
        self.depth.copy_to(&mut self.device.depth_scratch);
        let p = &mut self.device.pyramids[pyramid.0 as usize];
        p.build(&self.device.depth_scratch);
        let texels: Vec<u64> = p.sizes()[1..].iter().map(|&(w, h)| u64::from(w) * u64::from(h)).collect();
        let busy_before = self.clock.gpu_busy;
        for t in texels {
            self.dispatch_costing(t as f64 * self.model.gpu_pyramid_texel_ns * 1e-3);
        }
        self.count.stats.pyramid_ms += (self.clock.gpu_busy - busy_before) * 1e-3;
        self.late_from_us.get_or_insert(self.clock.gpu_busy);
    }

    fn test_boxes_pyramid(&mut self, boxes: BoxSet, ids: IdList, pyramid: Pyramid, reach: u32, flags: Flags) {
        let count = self.device.lists[ids.0 as usize].ids.len();
        let tested = self.boxes_to_test(boxes, ids, flags);
        let (width, height) = (self.depth.width(), self.depth.height());
        let p = &self.device.pyramids[pyramid.0 as usize];
        let mut fetched = 0u64;
        let mut visible = Vec::new();
        for (id, b) in &tested {
            let result = p.test(&box_footprint(&self.view_projection, width, height, b), reach);
            fetched += u64::from(result.fetched);
            if result.visible {
                visible.push(*id);
            }
        }
        let set = &mut self.device.flags[flags.0 as usize];
        visible.into_iter().for_each(|id| set[id as usize] = true);
        self.count.stats.query_boxes += tested.len() as u64;
        let m = &self.model;
        let work_ns = count as f64 * m.gpu_compute_item_ns
            + tested.len() as f64 * m.gpu_hiz_box_ns
            + fetched as f64 * m.gpu_hiz_texel_ns;
        self.dispatch_costing(work_ns * 1e-3);
    }

    fn expand(&mut self, src: IdList, filter: Flags, table: RangeTable, into: ExpandInto) {
        let gathered = self.device.gather(src, filter, table);
        self.dispatch(self.device.lists[src.0 as usize].ids.len() + gathered.len());
        self.device.put(gathered, into);
    }

    fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags) {
        let frustum = self.camera.expect("drop_outside_frustum outside a frame").frustum();
        let len = self.device.flags[flags.0 as usize].len();
        self.dispatch(len);
        self.device.drop_outside_frustum(boxes, flags, &frustum);
    }

    fn compact(&mut self, flags: Flags, unless: Option<Flags>, dst: IdList) {
        let ids = self.device.compacted(flags, unless);
        self.dispatch(self.device.flags[flags.0 as usize].len());
        self.device.lists[dst.0 as usize].set(ids);
    }

    fn draw_list(&mut self, list: IdList) {
        let ids = std::mem::take(&mut self.device.lists[list.0 as usize].ids);
        // The dispatch writing one set of draw arguments per id.
        self.dispatch(ids.len());
        self.indirect_draw(RenderState::Indirect);
        for &i in &ids {
            if !self.scene.instances[i as usize].enabled {
                continue;
            }
            self.count.stats.indirect_draw_calls += 1;
            self.draw_instance(i, self.model.gpu_indirect_draw_us);
        }
        self.device.lists[list.0 as usize].ids = ids;
    }

    fn read_count(&mut self, list: IdList) -> u32 {
        self.read_back();
        self.device.lists[list.0 as usize].ids.len() as u32
    }

    fn read_list(&mut self, list: IdList) -> Vec<u32> {
        self.read_back();
        self.device.lists[list.0 as usize].ids.clone()
    }

    fn read_flags(&mut self, flags: Flags) -> Vec<bool> {
        self.read_back();
        self.device.flags[flags.0 as usize].clone()
    }
}
