//! `occlude bench --dump-frame K`: PNGs of what a method decided in one frame,
//! for a visual check. For `om`, `METHOD-frame-K-occupancy.png` shows the
//! occupancy map at the end of stage 1 (covered cells dark, clear cells
//! light) scaled to the frame by nearest neighbour, and
//! `METHOD-frame-K-stages.png` the frame's depth image with the screen
//! rectangle of every node outlined in the colour of what became of it.

use super::plot::{register_font, FONT};
use anyhow::{ensure, Context, Result};
use occlude_bench::runner::FrameDump;
use occlude_core::methods::{NdcRect, NodeClass};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Colour of a covered occupancy-map cell.
const COVERED: RGBColor = RGBColor(45, 45, 60);
/// Colour of a clear occupancy-map cell.
const CLEAR: RGBColor = RGBColor(235, 235, 225);

/// Outline colour and legend text of each class of node.
fn style(class: NodeClass) -> (RGBColor, &'static str) {
    match class {
        NodeClass::DrawnWithoutQuery => (RGBColor(0, 200, 70), "drawn in stage 1 (no query)"),
        NodeClass::DrawnAfterQuery => (RGBColor(20, 110, 255), "drawn after a stage-2 query"),
        NodeClass::FoundHidden => (RGBColor(230, 30, 30), "found hidden in stage 2"),
    }
}

/// Writes both PNGs of `dump` into `dir` (created if missing); returns their
/// paths, occupancy map first.
pub fn write(dump: &FrameDump, dir: &Path) -> Result<Vec<PathBuf>> {
    let (w, h) = dump.resolution;
    let v = &dump.view;
    ensure!(dump.depth.len() == w as usize * h as usize, "depth image does not match {w}x{h}");
    ensure!(v.occupancy.len() == v.map_width as usize * v.map_height as usize, "occupancy map has the wrong size");
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let name = |what: &str| dir.join(format!("{}-frame-{}-{what}.png", dump.method, dump.frame));
    let (occupancy, stages) = (name("occupancy"), name("stages"));
    write_png(&occupancy, dump.resolution, &occupancy_pixels(dump), |_| Ok(()))?;
    register_font()?;
    write_png(&stages, dump.resolution, &depth_pixels(&dump.depth), |root| draw_nodes(dump, root))?;
    Ok(vec![occupancy, stages])
}

/// Writes the RGB image `pixels` of `size` to `path` as a PNG, with
/// `overlay` drawn on top.
fn write_png(
    path: &Path,
    size: (u32, u32),
    pixels: &[u8],
    overlay: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    let written = (|| -> Result<()> {
        let mut backend = BitMapBackend::new(path, size);
        backend.blit_bitmap((0, 0), size, pixels)?;
        let root = backend.into_drawing_area();
        overlay(&root)?;
        root.present()?;
        Ok(())
    })();
    written.with_context(|| format!("writing {}", path.display()))
}

/// The occupancy map scaled to the frame by nearest neighbour, as RGB.
fn occupancy_pixels(dump: &FrameDump) -> Vec<u8> {
    let (w, h) = (dump.resolution.0 as u64, dump.resolution.1 as u64);
    let v = &dump.view;
    let (mw, mh) = (v.map_width as u64, v.map_height as u64);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (y * mh / h * mw + x * mw / w) as usize))
        .flat_map(|cell| {
            let RGBColor(r, g, b) = if v.occupancy[cell] { COVERED } else { CLEAR };
            [r, g, b]
        })
        .collect()
}

/// The depth image as grey levels, near dark and far light over the range
/// of depths drawn; white where nothing was drawn.
fn depth_pixels(depth: &[f32]) -> Vec<u8> {
    let drawn = || depth.iter().copied().filter(|&d| d < 1.0);
    let lo = drawn().fold(f32::INFINITY, f32::min);
    let hi = drawn().fold(f32::NEG_INFINITY, f32::max);
    let span = (hi - lo).max(f32::EPSILON);
    depth
        .iter()
        .flat_map(|&d| {
            let grey = if d < 1.0 { 40.0 + 170.0 * (d - lo) / span } else { 255.0 };
            [grey as u8; 3]
        })
        .collect()
}

/// The pixel corners of an NDC rectangle on an image of `size`, kept a
/// little past the edges so that off-screen sides stay off-screen.
fn pixel_rect(r: &NdcRect, (w, h): (u32, u32)) -> [(i32, i32); 2] {
    let (w, h) = (w as f32, h as f32);
    let x = |v: f32| ((v + 1.0) * 0.5 * w).clamp(-2.0, w + 1.0) as i32;
    let y = |v: f32| ((1.0 - v) * 0.5 * h).clamp(-2.0, h + 1.0) as i32;
    [(x(r.min.x), y(r.max.y)), (x(r.max.x), y(r.min.y))]
}

/// Outlines every node's rectangle in its class's colour and adds a legend
/// with the count of each class.
fn draw_nodes(dump: &FrameDump, root: &DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()> {
    for class in NodeClass::ALL {
        let (colour, _) = style(class);
        for (_, r) in dump.view.nodes.iter().filter(|(c, _)| *c == class) {
            root.draw(&Rectangle::new(pixel_rect(r, dump.resolution), colour.stroke_width(1)))?;
        }
    }
    let line = 18;
    let legend_height = line * (NodeClass::ALL.len() as i32 + 1) + 8;
    root.draw(&Rectangle::new([(4, 4), (330, 4 + legend_height)], WHITE.mix(0.85).filled()))?;
    root.draw(&Rectangle::new([(4, 4), (330, 4 + legend_height)], BLACK.stroke_width(1)))?;
    let text = (FONT, 14).into_font().color(&BLACK);
    root.draw(&Text::new(format!("{}, frame {}", dump.method, dump.frame), (10, 8), text.clone()))?;
    for (i, class) in NodeClass::ALL.into_iter().enumerate() {
        let (colour, label) = style(class);
        let top = 8 + line * (i as i32 + 1);
        let count = dump.view.nodes.iter().filter(|(c, _)| *c == class).count();
        root.draw(&Rectangle::new([(10, top + 2), (30, top + 12)], colour.filled()))?;
        root.draw(&Text::new(format!("{label}: {count}"), (36, top), text.clone()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;
    use occlude_core::methods::DebugView;

    /// A 400x300 frame, drawn in its bottom third, with a 4x2 map (its left
    /// column covered) and one node of each class side by side below the
    /// legend.
    fn sample() -> FrameDump {
        let rect = |x0: f32, y0: f32, x1: f32, y1: f32| NdcRect { min: Vec2::new(x0, y0), max: Vec2::new(x1, y1) };
        let mut depth = vec![1.0; 400 * 300];
        depth[400 * 200..].fill(0.5);
        FrameDump {
            method: "om".into(),
            frame: 3,
            resolution: (400, 300),
            depth,
            view: DebugView {
                map_width: 4,
                map_height: 2,
                occupancy: vec![true, false, false, false, true, false, false, false],
                nodes: vec![
                    (NodeClass::DrawnWithoutQuery, rect(-0.9, -0.9, -0.5, -0.5)),
                    (NodeClass::DrawnAfterQuery, rect(-0.2, -0.9, 0.2, -0.5)),
                    (NodeClass::FoundHidden, rect(0.5, -0.9, 0.9, -0.5)),
                ],
            },
        }
    }

    fn decode(path: &Path) -> image::RgbImage {
        image::open(path).unwrap().to_rgb8()
    }

    #[test]
    fn writes_occupancy_map_and_outlined_nodes() {
        let dir = tempfile::tempdir().unwrap();
        let paths = write(&sample(), &dir.path().join("new")).unwrap();
        let names: Vec<_> = paths.iter().map(|p| p.file_name().unwrap().to_str().unwrap()).collect();
        assert_eq!(names, ["om-frame-3-occupancy.png", "om-frame-3-stages.png"]);

        let map = decode(&paths[0]);
        assert_eq!(map.dimensions(), (400, 300));
        let rgb = |c: RGBColor| image::Rgb([c.0, c.1, c.2]);
        // Cells are 100 pixels wide: column 0 covered, the rest clear.
        assert_eq!(*map.get_pixel(0, 0), rgb(COVERED));
        assert_eq!(*map.get_pixel(99, 299), rgb(COVERED));
        assert_eq!(*map.get_pixel(100, 0), rgb(CLEAR));
        assert_eq!(*map.get_pixel(399, 299), rgb(CLEAR));

        let stages = decode(&paths[1]);
        assert_eq!(stages.dimensions(), (400, 300));
        // The left edge of each node's rectangle, at mid-height (y = -0.7 in
        // NDC is pixel row 255), in its class's colour: x = -0.9, -0.2, 0.5.
        for (class, x) in NodeClass::ALL.into_iter().zip([20, 160, 300]) {
            assert_eq!(*stages.get_pixel(x, 255), rgb(style(class).0), "{class:?}");
        }
        // The depth image underneath: drawn pixels grey, the rest white.
        assert_eq!(*stages.get_pixel(130, 270), image::Rgb([40, 40, 40]));
        assert_eq!(*stages.get_pixel(130, 150), image::Rgb([255, 255, 255]));
    }

    #[test]
    fn mismatched_sizes_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut d = sample();
        d.view.occupancy.pop();
        assert!(write(&d, dir.path()).unwrap_err().to_string().contains("occupancy"));
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
    }
}
