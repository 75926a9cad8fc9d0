//! [`Shading`]: what a drawn fragment costs, as the three tests of the CHC++
//! paper's Figure 9 shade the Powerplant (section 8): a depth-only pass
//! (DP), the model's fixed-pipeline material shading (FIX), and a shader of
//! 40 texture lookups (SH). Each setting changes one cost of a
//! [`GpuModel`], `gpu_fragment_ns`; queries, boxes and every other cost
//! stay the model's.

use crate::GpuModel;
use std::fmt;
use std::str::FromStr;

/// Texture lookups per fragment of the paper's SH shader (section 8: "the
/// shader has 40 texture lookups").
pub const SHADER_LOOKUPS: f64 = 40.0;

/// Pixels the paper's GPU writes per texel its texture units filter: the
/// GeForce 8800 GTX (section 8) at 575 MHz writes 13.8 Gpixel/s with its 24
/// ROPs and filters 36.8 Gtexel/s with its 64 texture units (Tom's
/// Hardware, "GeForce 8800: Here Comes the DX10 Boom", 2006; ComputerBase's
/// 8800 GTX review gives the same two rates).
pub const PIXELS_PER_TEXEL: f64 = 13.8 / 36.8;

/// How the simulated GPU shades drawn fragments (`--shading`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// `dp`: depth only. A drawn fragment costs what a query fragment
    /// costs (`gpu_query_fragment_ns`: the depth test and write, no
    /// colour), the model's own depth-only rate.
    DepthOnly,
    /// `fix`: the model as it is (`gpu_fragment_ns`), which its sources
    /// give for colour and depth written by fixed-pipeline shading.
    #[default]
    Fixed,
    /// `sh`: fixed shading plus [`SHADER_LOOKUPS`] texture lookups, each
    /// costing [`PIXELS_PER_TEXEL`] of a shaded pixel: the 8800 GTX's ratio
    /// of texel rate to pixel rate carried over to the model. Assumptions,
    /// no source: the shader is bound by its lookups (its arithmetic hidden
    /// behind them), each a bilinear texel at the units' peak rate, and
    /// the ratio holds on the model's GPU.
    Shader,
}

impl Shading {
    /// The settings, in the paper's order.
    pub const ALL: [Shading; 3] = [Shading::DepthOnly, Shading::Fixed, Shading::Shader];

    /// The paper's name of the setting (DP, FIX, SH).
    pub fn paper_name(self) -> &'static str {
        match self {
            Shading::DepthOnly => "DP",
            Shading::Fixed => "FIX",
            Shading::Shader => "SH",
        }
    }
}

impl fmt::Display for Shading {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Shading::DepthOnly => "dp",
            Shading::Fixed => "fix",
            Shading::Shader => "sh",
        })
    }
}

impl FromStr for Shading {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Shading::ALL
            .into_iter()
            .find(|shading| shading.to_string() == s)
            .ok_or_else(|| format!("unknown shading '{s}': expected dp, fix or sh"))
    }
}

impl GpuModel {
    /// The model with drawn fragments shaded as `shading` says; its name
    /// gets `+dp` or `+sh` (`fix` leaves the model as it is).
    pub fn with_shading(mut self, shading: Shading) -> Self {
        self.gpu_fragment_ns = match shading {
            Shading::DepthOnly => self.gpu_query_fragment_ns,
            Shading::Fixed => return self,
            Shading::Shader => self.gpu_fragment_ns * (1.0 + SHADER_LOOKUPS * PIXELS_PER_TEXEL),
        };
        self.name = format!("{}+{shading}", self.name);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shading_orders_the_fragment_cost_and_names_the_model() {
        let model = GpuModel::modern();
        let [dp, fix, sh] = Shading::ALL.map(|s| model.clone().with_shading(s));
        assert!(dp.gpu_fragment_ns < fix.gpu_fragment_ns && fix.gpu_fragment_ns < sh.gpu_fragment_ns);
        assert_eq!(dp.gpu_fragment_ns, model.gpu_query_fragment_ns);
        assert_eq!(fix, model);
        // 40 lookups at 0.375 pixels each: 16 times a fixed-shaded pixel.
        assert!((sh.gpu_fragment_ns / fix.gpu_fragment_ns - 16.0).abs() < 1e-9);
        assert_eq!((dp.name.as_str(), sh.name.as_str()), ("modern+dp", "modern+sh"));
        // Only the fragment cost changes.
        assert_eq!(GpuModel { gpu_fragment_ns: model.gpu_fragment_ns, name: model.name.clone(), ..sh }, model);
        for s in Shading::ALL {
            assert_eq!(s.to_string().parse::<Shading>(), Ok(s));
        }
        assert!("phong".parse::<Shading>().is_err());
    }
}
