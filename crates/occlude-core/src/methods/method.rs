//! [`Method`]: every culling method with its parameters as Rust types. The
//! command line's strings parse into it ([`Method::parse`]); a program
//! builds it directly, e.g. `Method::Hiz(HizParams { texels: 4, ..Default::default() })`.

use super::auto::{Auto, AutoParams};
use super::chc::{Chc, ChcParams};
use super::chcpp::{Chcpp, ChcppParams};
use super::hiz::{HizParams, TwoPhaseHiZ};
use super::ioc::{IocParams, IterativeOcclusion};
use super::moc::{MaskedOcclusion, MocParams};
use super::nocull::NoCulling;
use super::nohc::{Estimate, Nohc};
use super::om::{OccupancyMap, OmParams};
use super::opt::{OptParams, Optimal};
use super::options::{list_params, read_params, MethodOptions, MethodParams, OptionError, ParamVisitor};
use super::roc::{RasterOcclusion, RocParams};
use super::sw::StopAndWait;
use super::vfc::ViewFrustumCulling;
use super::{CullingMethod, MethodError};
use std::fmt;
use std::str::FromStr;

/// A culling method and its parameters. [`Default`] is each method's
/// published setting; [`Method::build`] checks the values and makes the
/// method. `FromStr` takes a name with default parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// `vfc`: view-frustum culling, the baseline every method is checked against.
    Vfc,
    /// `sw`: hierarchical stop-and-wait occlusion queries.
    Sw,
    /// `chc`: coherent hierarchical culling (Bittner et al. 2004).
    Chc(ChcParams),
    /// `chcpp`: CHC++ (Mattausch et al. 2008).
    Chcpp(ChcppParams),
    /// `om`: occupancy map with multiple queries (Staneker et al.).
    Om(OmParams),
    /// `roc`: raster occlusion culling, GPU-driven.
    Roc(RocParams),
    /// `ioc`: iterative occlusion culling, GPU-driven, level by level.
    Ioc(IocParams),
    /// `hiz`: two-phase culling against a depth pyramid, GPU-driven.
    Hiz(HizParams),
    /// `moc`: masked software occlusion culling on the CPU.
    Moc(MocParams),
    /// `opt`: the oracle's visible set, a lower bound (not conservative in
    /// the sense of a method: it needs the oracle pass).
    Opt(OptParams),
    /// `nohc`: near-optimal hierarchical culling, costs from the model.
    Nohc,
    /// `nohc-opt`: NOHC with the oracle's exact visibility.
    NohcOpt,
    /// `auto`: `roc`, `hiz`, `chcpp` or `vfc` per frame, whichever its
    /// frames measure fastest ([`Auto`]); the method to start with.
    Auto(AutoParams),
    /// `nocull`: every instance drawn, not even the frustum tested (the IOC
    /// poster's NOCULL baseline).
    NoCull,
}

impl Method {
    /// The method's name on the command line and in JSON.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Vfc => "vfc",
            Method::Sw => "sw",
            Method::Chc(_) => "chc",
            Method::Chcpp(_) => "chcpp",
            Method::Om(_) => "om",
            Method::Roc(_) => "roc",
            Method::Ioc(_) => "ioc",
            Method::Hiz(_) => "hiz",
            Method::Moc(_) => "moc",
            Method::Opt(_) => "opt",
            Method::Nohc => "nohc",
            Method::NohcOpt => "nohc-opt",
            Method::Auto(_) => "auto",
            Method::NoCull => "nocull",
        }
    }

    /// The method called `name` with its defaults.
    pub fn named(name: &str) -> Result<Self, MethodError> {
        Ok(match name {
            "vfc" => Method::Vfc,
            "sw" => Method::Sw,
            "chc" => Method::Chc(ChcParams::default()),
            "chcpp" => Method::Chcpp(ChcppParams::default()),
            "om" => Method::Om(OmParams::default()),
            "roc" => Method::Roc(RocParams::default()),
            "ioc" => Method::Ioc(IocParams::default()),
            "hiz" => Method::Hiz(HizParams::default()),
            "moc" => Method::Moc(MocParams::default()),
            "opt" => Method::Opt(OptParams::default()),
            "nohc" => Method::Nohc,
            "nohc-opt" => Method::NohcOpt,
            "auto" => Method::Auto(AutoParams::default()),
            "nocull" => Method::NoCull,
            _ => return Err(MethodError::Unknown(name.to_string())),
        })
    }

    /// The method called `name` with `options`' values for it (the command
    /// line's `--method-opt`) over its defaults.
    pub fn parse(name: &str, options: &MethodOptions) -> Result<Self, MethodError> {
        let mut method = Self::named(name)?;
        read_params(name, options, |v| method.visit(v))?;
        Ok(method)
    }

    /// `(parameter, value)` pairs as the command line writes them, in the
    /// method's order; an error for a value out of its range.
    pub fn params(&self) -> Result<Vec<(String, String)>, OptionError> {
        list_params(self.name(), |v| self.clone().visit(v))
    }

    /// Whether the method runs on the backend's GPU-resident culling (its
    /// tests and draw lists stay on the device): `roc`, `ioc`, `hiz`.
    pub fn is_gpu_driven(&self) -> bool {
        matches!(self, Method::Roc(_) | Method::Ioc(_) | Method::Hiz(_))
    }

    /// The method, freshly made (no state from earlier frames), after its
    /// parameters are checked.
    pub fn build(&self) -> Result<Box<dyn CullingMethod + Send>, MethodError> {
        self.params()?;
        Ok(match self.clone() {
            Method::Vfc => Box::new(ViewFrustumCulling),
            Method::Sw => Box::new(StopAndWait),
            Method::Chc(p) => Box::new(Chc::new(p)),
            Method::Chcpp(p) => Box::new(Chcpp::new(p)),
            Method::Om(p) => Box::new(OccupancyMap::new(p)),
            Method::Roc(p) => Box::new(RasterOcclusion::new(p)),
            Method::Ioc(p) => Box::new(IterativeOcclusion::new(p)),
            Method::Hiz(p) => Box::new(TwoPhaseHiZ::new(p)),
            Method::Moc(p) => Box::new(MaskedOcclusion::new(p)),
            Method::Opt(p) => Box::new(Optimal::new(p)),
            Method::Nohc => Box::new(Nohc::new(Estimate::Model)),
            Method::NohcOpt => Box::new(Nohc::new(Estimate::Oracle)),
            Method::Auto(p) => Box::new(Auto::new(p)),
            Method::NoCull => Box::new(NoCulling),
        })
    }

    /// Visits the parameters of the method (none for those without).
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        match self {
            Method::Chc(p) => p.visit(v),
            Method::Chcpp(p) => p.visit(v),
            Method::Om(p) => p.visit(v),
            Method::Roc(p) => p.visit(v),
            Method::Ioc(p) => p.visit(v),
            Method::Hiz(p) => p.visit(v),
            Method::Moc(p) => p.visit(v),
            Method::Opt(p) => p.visit(v),
            Method::Auto(p) => p.visit(v),
            Method::Vfc | Method::Sw | Method::Nohc | Method::NohcOpt | Method::NoCull => Ok(()),
        }
    }
}

/// `auto`: the method the docs recommend, never much slower than `vfc`.
impl Default for Method {
    fn default() -> Self {
        Method::Auto(AutoParams::default())
    }
}

/// The method's name.
impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name with default parameters (`"hiz".parse()`).
impl FromStr for Method {
    type Err = MethodError;
    fn from_str(name: &str) -> Result<Self, MethodError> {
        Self::named(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::METHOD_NAMES;

    #[test]
    fn every_name_parses_to_its_method_and_back() {
        for name in METHOD_NAMES {
            let method: Method = name.parse().unwrap();
            assert_eq!(method.name(), name);
            assert_eq!(method.build().unwrap().name(), name);
        }
        assert!(matches!("zzz".parse::<Method>(), Err(MethodError::Unknown(_))));
    }

    #[test]
    fn strings_and_types_make_the_same_method() {
        let options = MethodOptions::parse(&["hiz.texels=4", "chc.tav=2"]).unwrap();
        let typed = Method::Hiz(HizParams { texels: 4, ..Default::default() });
        assert_eq!(Method::parse("hiz", &options).unwrap(), typed);
        assert!(typed.params().unwrap().contains(&("texels".into(), "4".into())));
        let err = Method::Hiz(HizParams { texels: 0, ..Default::default() }).build().err().unwrap();
        assert!(err.to_string().contains("hiz.texels = 0: expected an integer from 1 to 16"), "{err}");
        assert!(Method::parse("vfc", &MethodOptions::parse(&["vfc.x=1"]).unwrap()).is_err());
    }
}
