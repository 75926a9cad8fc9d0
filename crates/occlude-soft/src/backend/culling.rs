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
//! done. The CPU pays `cpu_dispatch_us` to record each dispatch or indirect
//! draw.
//!
//! Results are those of the wgpu backend's compute and raster passes: the
//! same padded box proxies, depth bias and near-region rule as the
//! CPU-driven queries (`occlude_core::query_box`), so a box is visible here
//! exactly when an occlusion query over it would count a pixel.

use super::{charge_gpu_time, GpuOp, SoftBackend};
use crate::raster::{CommandKind, DepthTest};
use occlude_core::query_box::padded;
use occlude_core::{Aabb, BoxSet, ExpandInto, Flags, GpuCulling, IdList, ItemRange, RangeTable, RenderState};

/// The soft backend's "device memory": every resource created so far.
#[derive(Default)]
pub(super) struct Device {
    /// Padded boxes; `None` for an empty box, which never tests visible.
    boxes: Vec<Vec<Option<Aabb>>>,
    flags: Vec<Vec<bool>>,
    lists: Vec<List>,
    tables: Vec<Table>,
}

/// An id list and the most ids it may hold.
struct List {
    ids: Vec<u32>,
    capacity: usize,
}

/// Per id, a range of `items`.
struct Table {
    ranges: Vec<ItemRange>,
    items: Vec<u32>,
}

impl Table {
    fn items_of(&self, id: u32) -> &[u32] {
        let r = self.ranges[id as usize];
        &self.items[r.first as usize..(r.first + r.count) as usize]
    }
}

impl List {
    /// Replaces the ids; a list never holds more than its capacity (the GPU
    /// would write past its buffer: a caller's bug).
    fn set(&mut self, ids: Vec<u32>) {
        assert!(ids.len() <= self.capacity, "{} ids into a list of capacity {}", ids.len(), self.capacity);
        self.ids = ids;
    }
}

impl SoftBackend<'_> {
    /// Charges one compute dispatch over `items` elements, after everything
    /// recorded before it has run.
    fn dispatch(&mut self, items: usize) {
        self.flush();
        self.count.stats.dispatches += 1;
        self.clock.cpu_work(self.model.cpu_dispatch_us);
        self.culling_work(self.model.gpu_dispatch_us + items as f64 * self.model.gpu_compute_item_ns * 1e-3);
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

impl GpuCulling for SoftBackend<'_> {
    fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        let set = boxes.iter().map(|b| (!b.is_empty()).then(|| padded(b))).collect();
        self.device.boxes.push(set);
        BoxSet(self.device.boxes.len() as u32 - 1)
    }

    fn create_flags(&mut self, len: u32) -> Flags {
        self.device.flags.push(vec![false; len as usize]);
        Flags(self.device.flags.len() as u32 - 1)
    }

    fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        let mut list = List { ids: Vec::new(), capacity: capacity as usize };
        list.set(ids.to_vec());
        self.device.lists.push(list);
        IdList(self.device.lists.len() as u32 - 1)
    }

    fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        assert!(ranges.iter().all(|r| r.first as usize + r.count as usize <= items.len()), "a range past the items");
        self.device.tables.push(Table { ranges: ranges.to_vec(), items: items.to_vec() });
        RangeTable(self.device.tables.len() as u32 - 1)
    }

    fn clear_flags(&mut self, flags: Flags) {
        let len = self.device.flags[flags.0 as usize].len();
        self.dispatch(len);
        self.device.flags[flags.0 as usize].fill(false);
    }

    fn test_boxes(&mut self, boxes: BoxSet, ids: IdList, flags: Flags) {
        let camera = self.camera.expect("test_boxes outside a frame");
        let frustum = camera.frustum();
        let count = self.device.lists[ids.0 as usize].ids.len();
        self.dispatch(count);
        // The dispatch: near boxes are visible untested, boxes outside the
        // frustum hidden, the rest go to the raster list.
        let mut raster = Vec::new();
        for k in 0..count {
            let id = self.device.lists[ids.0 as usize].ids[k];
            let Some(b) = self.device.boxes[boxes.0 as usize][id as usize] else { continue };
            if camera.box_touches_near_region(&b) {
                self.device.flags[flags.0 as usize][id as usize] = true;
            } else if frustum.intersects(&b) {
                raster.push((id, b));
            }
        }
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

    fn expand(&mut self, src: IdList, filter: Flags, table: RangeTable, into: ExpandInto) {
        let d = &self.device;
        let pass = &d.flags[filter.0 as usize];
        let t = &d.tables[table.0 as usize];
        let src_ids = &d.lists[src.0 as usize].ids;
        let gathered: Vec<u32> =
            src_ids.iter().filter(|&&id| pass[id as usize]).flat_map(|&id| t.items_of(id).iter().copied()).collect();
        self.dispatch(src_ids.len() + gathered.len());
        match into {
            ExpandInto::List(list) => self.device.lists[list.0 as usize].set(gathered),
            ExpandInto::Flags(flags) => {
                let set = &mut self.device.flags[flags.0 as usize];
                gathered.into_iter().for_each(|i| set[i as usize] = true);
            }
        }
    }

    fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags) {
        let frustum = self.camera.expect("drop_outside_frustum outside a frame").frustum();
        let len = self.device.flags[flags.0 as usize].len();
        self.dispatch(len);
        let set = &mut self.device.flags[flags.0 as usize];
        for (flag, b) in set.iter_mut().zip(&self.device.boxes[boxes.0 as usize]) {
            *flag &= b.is_some_and(|b| frustum.intersects(&b));
        }
    }

    fn compact(&mut self, flags: Flags, unless: Option<Flags>, dst: IdList) {
        let d = &self.device;
        let set = &d.flags[flags.0 as usize];
        let except = unless.map(|u| &d.flags[u.0 as usize]);
        let ids: Vec<u32> =
            (0..set.len()).filter(|&k| set[k] && !except.is_some_and(|e| e[k])).map(|k| k as u32).collect();
        self.dispatch(set.len());
        self.device.lists[dst.0 as usize].set(ids);
    }

    fn draw_list(&mut self, list: IdList) {
        let ids = std::mem::take(&mut self.device.lists[list.0 as usize].ids);
        // The dispatch writing one set of draw arguments per id.
        self.dispatch(ids.len());
        self.indirect_draw(RenderState::Indirect);
        for &i in &ids {
            self.count.stats.indirect_draw_calls += 1;
            self.draw_instance(i, self.model.gpu_indirect_draw_us);
        }
        self.device.lists[list.0 as usize].ids = ids;
    }

    fn read_count(&mut self, list: IdList) -> u32 {
        self.flush();
        self.count.stats.readbacks += 1;
        let ready = self.clock.gpu_free + self.model.readback_us;
        self.clock.wait_until(ready);
        self.device.lists[list.0 as usize].ids.len() as u32
    }
}
