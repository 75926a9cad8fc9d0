//! The statistics overlay: lines of text drawn with plotters' bitmap backend
//! and the DejaVu Sans font the `dejavu` crate embeds (as the PNG plots are),
//! turned into an RGBA image (white text on a translucent dark panel),
//! uploaded as a texture and blended over the frame's top-left corner.

use super::present::{draw_image, Blit};
use crate::bench::plot::{register_font, FONT};
use anyhow::Result;
use occlude_core::FrameStats;
use plotters::prelude::*;

/// Seconds between two refreshes of the text (the numbers are averaged over
/// the frames in between).
pub const REFRESH_SECONDS: f32 = 0.25;

/// Font size in pixels.
const FONT_SIZE: u32 = 15;
/// Pixels from one line of text to the next.
const LINE_HEIGHT: u32 = 19;
/// Pixels between the panel's edge and its text, and between the panel and
/// the window's corner.
const MARGIN: u32 = 8;
/// Widest panel, pixels.
const MAX_WIDTH: u32 = 600;
/// Opacity of the panel behind the text.
const PANEL_ALPHA: f32 = 0.6;

/// Frame statistics gathered between two refreshes of the overlay.
#[derive(Clone, Debug, Default)]
pub struct StatsAverage(Vec<FrameStats>);

/// The averaged figures the overlay shows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShownStats {
    /// Frame time, ms (begin to GPU idle, as `bench --backend wgpu` measures).
    pub frame_ms: f64,
    /// Time blocked on query results, ms.
    pub wait_ms: f64,
    /// Occlusion queries per frame.
    pub queries: f64,
    /// Draw calls per frame.
    pub draw_calls: f64,
    /// State changes (switches between drawing and querying) per frame.
    pub state_changes: f64,
    /// Material switches per frame.
    pub material_switches: f64,
    /// Triangles drawn per frame.
    pub triangles: f64,
    /// Distinct objects drawn per frame.
    pub visible_objects: f64,
}

impl StatsAverage {
    /// Adds one frame.
    pub fn add(&mut self, stats: FrameStats) {
        self.0.push(stats);
    }

    /// The mean of the frames added since the last call, or `None` if none was.
    pub fn take(&mut self) -> Option<ShownStats> {
        let frames = std::mem::take(&mut self.0);
        let n = frames.len() as f64;
        let mean = |f: fn(&FrameStats) -> f64| frames.iter().map(f).sum::<f64>() / n;
        (!frames.is_empty()).then(|| ShownStats {
            frame_ms: mean(|s| s.frame_ms),
            wait_ms: mean(|s| s.wait_ms),
            queries: mean(|s| s.queries as f64),
            draw_calls: mean(|s| s.draw_calls as f64),
            state_changes: mean(|s| s.state_changes as f64),
            material_switches: mean(|s| s.material_switches as f64),
            triangles: mean(|s| s.triangles as f64),
            visible_objects: mean(|s| s.visible_objects as f64),
        })
    }
}

impl ShownStats {
    /// The statistics as overlay lines.
    pub fn lines(&self) -> [String; 3] {
        [
            format!("frame {:.2} ms   wait {:.2} ms", self.frame_ms, self.wait_ms),
            format!(
                "queries {:.0}   draw calls {:.0}   state changes {:.0}   material switches {:.0}",
                self.queries, self.draw_calls, self.state_changes, self.material_switches
            ),
            format!("triangles {}   visible objects {:.0}", thousands(self.triangles), self.visible_objects),
        ]
    }
}

/// `1234567.0` as `1,234,567`.
fn thousands(v: f64) -> String {
    let digits = format!("{:.0}", v.max(0.0));
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// An RGBA image of `lines` on a panel at most `max_width` x `max_height`
/// pixels (less when the text needs less height); `None` when no panel fits.
pub fn text_image(lines: &[String], max_width: u32, max_height: u32) -> Result<Option<(u32, u32, Vec<u8>)>> {
    let width = max_width.min(MAX_WIDTH);
    let height = max_height.min(2 * MARGIN + LINE_HEIGHT * lines.len() as u32);
    if width == 0 || height == 0 {
        return Ok(None);
    }
    register_font()?;
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        let style = (FONT, FONT_SIZE).into_font().color(&WHITE);
        for (i, line) in lines.iter().enumerate() {
            let top = (MARGIN + i as u32 * LINE_HEIGHT) as i32;
            root.draw(&Text::new(line.as_str(), (MARGIN as i32, top), style.clone()))
                .map_err(|e| anyhow::anyhow!("drawing the overlay text: {e}"))?;
        }
        root.present().map_err(|e| anyhow::anyhow!("drawing the overlay text: {e}"))?;
    }
    // White text over black: the brightness is the text's coverage.
    let rgba = rgb
        .chunks_exact(3)
        .flat_map(|p| {
            let coverage = f32::from(p[0].max(p[1]).max(p[2])) / 255.0;
            let alpha = PANEL_ALPHA + (1.0 - PANEL_ALPHA) * coverage;
            [p[0], p[1], p[2], (alpha * 255.0).round() as u8]
        })
        .collect();
    Ok(Some((width, height, rgba)))
}

/// The overlay's texture and how it is drawn.
pub struct Overlay {
    pipeline: wgpu::RenderPipeline,
    image: Option<(wgpu::Texture, wgpu::BindGroup)>,
}

impl Overlay {
    /// An empty overlay drawn into targets of `format`.
    pub fn new(device: &wgpu::Device, blit: &Blit, format: wgpu::TextureFormat) -> Self {
        Self { pipeline: blit.pipeline(device, format, true), image: None }
    }

    /// Shows `lines` from now on, on a panel that fits a target of
    /// `target_size` pixels.
    pub fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        blit: &Blit,
        lines: &[String],
        (target_w, target_h): (u32, u32),
    ) -> Result<()> {
        let fit = |side: u32| side.saturating_sub(2 * MARGIN);
        let Some((width, height, rgba)) = text_image(lines, fit(target_w), fit(target_h))? else {
            self.image = None;
            return Ok(());
        };
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        if self.image.as_ref().is_none_or(|(t, _)| t.size() != size) {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("overlay"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let group = blit.bind(device, &texture.create_view(&Default::default()));
            self.image = Some((texture, group));
        }
        let (texture, _) = self.image.as_ref().expect("created above");
        queue.write_texture(
            texture.as_image_copy(),
            &rgba,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * 4), rows_per_image: Some(height) },
            size,
        );
        Ok(())
    }

    /// Encodes blending the text panel over the top-left corner of `target`.
    pub fn draw(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        if let Some((texture, group)) = &self.image {
            let rect = [MARGIN, MARGIN, texture.width(), texture.height()];
            draw_image(encoder, target, &self.pipeline, group, Some(rect));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averages_the_frames_since_the_last_refresh() {
        let mut avg = StatsAverage::default();
        assert_eq!(avg.take(), None);
        avg.add(FrameStats { frame_ms: 2.0, queries: 10, triangles: 1_000_000, ..FrameStats::default() });
        avg.add(FrameStats { frame_ms: 4.0, queries: 20, triangles: 3_000_000, ..FrameStats::default() });
        let shown = avg.take().unwrap();
        assert_eq!((shown.frame_ms, shown.queries), (3.0, 15.0));
        assert!(shown.lines()[2].contains("triangles 2,000,000"), "{:?}", shown.lines());
        assert_eq!(avg.take(), None, "taken");
    }

    #[test]
    fn text_is_drawn_on_a_translucent_panel() {
        let lines = vec!["chcpp on bvh".to_string(), "frame 1.00 ms".to_string()];
        let (w, h, rgba) = text_image(&lines, 300, 500).unwrap().unwrap();
        assert_eq!((w, h), (300, 2 * MARGIN + 2 * LINE_HEIGHT));
        let pixels: Vec<&[u8]> = rgba.chunks_exact(4).collect();
        let panel = (PANEL_ALPHA * 255.0).round() as u8;
        assert!(pixels.iter().any(|p| p[..3] == [255, 255, 255] && p[3] == 255), "white text");
        assert!(pixels.iter().filter(|p| p[..] == [0, 0, 0, panel]).count() > pixels.len() / 2, "panel");
        assert!(text_image(&lines, 0, 100).unwrap().is_none());
        let (_, clipped, _) = text_image(&lines, 300, 20).unwrap().unwrap();
        assert_eq!(clipped, 20);
    }

    #[test]
    fn thousands_are_grouped() {
        assert_eq!(thousands(0.0), "0");
        assert_eq!(thousands(999.0), "999");
        assert_eq!(thousands(1234567.4), "1,234,567");
    }
}
