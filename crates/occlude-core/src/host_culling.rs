//! [`HostResources`]: the resources of GPU-resident culling
//! ([`GpuCulling`](crate::GpuCulling)) held in CPU memory, with the compute
//! passes that only move ids and flags ([`GpuCulling::expand`],
//! [`GpuCulling::compact`], [`GpuCulling::drop_outside_frustum`]) as plain
//! loops. The soft backend's "device" and the mock backend's are these; each
//! answers the box tests its own way (rasterizing, or from a script) and
//! charges the passes on its own clock.
//!
//! [`GpuCulling::expand`]: crate::GpuCulling::expand
//! [`GpuCulling::compact`]: crate::GpuCulling::compact
//! [`GpuCulling::drop_outside_frustum`]: crate::GpuCulling::drop_outside_frustum

use crate::camera::Frustum;
use crate::depth_pyramid::DepthPyramid;
use crate::geometry::Aabb;
use crate::gpu_culling::{BoxSet, ExpandInto, Flags, IdList, ItemRange, Pyramid, RangeTable};
use crate::query_box::padded;

/// Every resource created so far, indexed by its handle.
#[derive(Debug, Default)]
pub struct HostResources {
    /// Per box set, its boxes grown as queries grow them
    /// ([`padded`]); `None` for an empty box, which never tests visible.
    pub boxes: Vec<Vec<Option<Aabb>>>,
    /// Per flag buffer, its flags.
    pub flags: Vec<Vec<bool>>,
    /// Per id list, its ids.
    pub lists: Vec<HostList>,
    /// Per range table, its ranges and items.
    pub tables: Vec<HostTable>,
    /// Per depth pyramid, its levels.
    pub pyramids: Vec<DepthPyramid>,
    /// The depth image a pyramid is built from, reused.
    pub depth_scratch: Vec<f32>,
}

/// An id list and the most ids it may hold.
#[derive(Debug)]
pub struct HostList {
    /// The ids.
    pub ids: Vec<u32>,
    capacity: usize,
}

impl HostList {
    /// Replaces the ids; a list never holds more than its capacity (the GPU
    /// would write past its buffer: a caller's bug, which panics).
    pub fn set(&mut self, ids: Vec<u32>) {
        assert!(ids.len() <= self.capacity, "{} ids into a list of capacity {}", ids.len(), self.capacity);
        self.ids = ids;
    }
}

/// Per id, a range of `items`.
#[derive(Debug)]
pub struct HostTable {
    ranges: Vec<ItemRange>,
    items: Vec<u32>,
}

impl HostTable {
    /// The items of id `id`.
    pub fn items_of(&self, id: u32) -> &[u32] {
        let r = self.ranges[id as usize];
        &self.items[r.first as usize..(r.first + r.count) as usize]
    }
}

impl HostResources {
    /// [`GpuCulling::create_boxes`](crate::GpuCulling::create_boxes).
    pub fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        self.boxes.push(boxes.iter().map(|b| (!b.is_empty()).then(|| padded(b))).collect());
        BoxSet(self.boxes.len() as u32 - 1)
    }

    /// [`GpuCulling::update_boxes`](crate::GpuCulling::update_boxes).
    pub fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]) {
        let set = &mut self.boxes[boxes.0 as usize];
        for (slot, b) in changed {
            set[*slot as usize] = (!b.is_empty()).then(|| padded(b));
        }
    }

    /// [`GpuCulling::release_all`](crate::GpuCulling::release_all).
    pub fn release_all(&mut self) {
        *self = Self::default();
    }

    /// [`GpuCulling::create_flags`](crate::GpuCulling::create_flags).
    pub fn create_flags(&mut self, len: u32) -> Flags {
        self.flags.push(vec![false; len as usize]);
        Flags(self.flags.len() as u32 - 1)
    }

    /// [`GpuCulling::write_flags`](crate::GpuCulling::write_flags).
    pub fn write_flags(&mut self, flags: Flags, set: &[bool]) {
        for (k, flag) in self.flags[flags.0 as usize].iter_mut().enumerate() {
            *flag = set.get(k).copied().unwrap_or(false);
        }
    }

    /// [`GpuCulling::copy_flags`](crate::GpuCulling::copy_flags).
    pub fn copy_flags(&mut self, src: Flags, dst: Flags) {
        let set = self.flags[src.0 as usize].clone();
        self.write_flags(dst, &set);
    }

    /// [`GpuCulling::create_list`](crate::GpuCulling::create_list).
    pub fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        let mut list = HostList { ids: Vec::new(), capacity: capacity as usize };
        list.set(ids.to_vec());
        self.lists.push(list);
        IdList(self.lists.len() as u32 - 1)
    }

    /// [`GpuCulling::create_table`](crate::GpuCulling::create_table).
    pub fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        assert!(ranges.iter().all(|r| r.first as usize + r.count as usize <= items.len()), "a range past the items");
        self.tables.push(HostTable { ranges: ranges.to_vec(), items: items.to_vec() });
        RangeTable(self.tables.len() as u32 - 1)
    }

    /// A depth pyramid over `width` x `height`, every texel at the far plane.
    pub fn create_pyramid(&mut self, width: u32, height: u32) -> Pyramid {
        self.pyramids.push(DepthPyramid::new(width, height));
        Pyramid(self.pyramids.len() as u32 - 1)
    }

    /// The items [`GpuCulling::expand`](crate::GpuCulling::expand) gathers:
    /// for each id of `src` whose flag in `filter` is set, its items in
    /// `table`.
    pub fn gather(&self, src: IdList, filter: Flags, table: RangeTable) -> Vec<u32> {
        let pass = &self.flags[filter.0 as usize];
        let t = &self.tables[table.0 as usize];
        let ids = &self.lists[src.0 as usize].ids;
        ids.iter().filter(|&&id| pass[id as usize]).flat_map(|&id| t.items_of(id).iter().copied()).collect()
    }

    /// Puts `items` where [`ExpandInto`] says: replacing a list's ids, or
    /// setting their flags.
    pub fn put(&mut self, items: Vec<u32>, into: ExpandInto) {
        match into {
            ExpandInto::List(list) => self.lists[list.0 as usize].set(items),
            ExpandInto::Flags(flags) => {
                let set = &mut self.flags[flags.0 as usize];
                items.into_iter().for_each(|i| set[i as usize] = true);
            }
        }
    }

    /// [`GpuCulling::drop_outside_frustum`](crate::GpuCulling::drop_outside_frustum)
    /// with the frame's `frustum`.
    pub fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags, frustum: &Frustum) {
        let set = &mut self.flags[flags.0 as usize];
        for (flag, b) in set.iter_mut().zip(&self.boxes[boxes.0 as usize]) {
            *flag &= b.is_some_and(|b| frustum.intersects(&b));
        }
    }

    /// The ids [`GpuCulling::compact`](crate::GpuCulling::compact) keeps:
    /// the set slots of `flags` not also set in `unless`.
    pub fn compacted(&self, flags: Flags, unless: Option<Flags>) -> Vec<u32> {
        let set = &self.flags[flags.0 as usize];
        let except = unless.map(|u| &self.flags[u.0 as usize]);
        (0..set.len()).filter(|&k| set[k] && !except.is_some_and(|e| e[k])).map(|k| k as u32).collect()
    }
}
