//! The typed run settings shared by the scene format, the command line, the engine and the
//! reports: iteration scheme, table precision and backend. Each is an enum with one spelling
//! (`Display`, `FromStr`, serde and `clap::ValueEnum` all use it), so no other code matches
//! strings.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Defines `Display`/`FromStr` from one table of (variant, spelling), and the list of accepted
/// spellings for error messages.
macro_rules! spelled {
    ($ty:ident, $what:literal, [$(($v:ident, $s:literal)),+ $(,)?]) => {
        impl $ty {
            /// The spelling used in scene files, on the command line and in reports.
            pub fn as_str(self) -> &'static str {
                match self {
                    $($ty::$v => $s,)+
                }
            }
        }
        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }
        impl FromStr for $ty {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                match s {
                    $($s => Ok($ty::$v),)+
                    _ => Err(format!(
                        concat!($what, " must be {}, got {:?}"),
                        [$(concat!("\"", $s, "\"")),+].join(" or "),
                        s
                    )),
                }
            }
        }
    };
}

/// Iteration scheme of §2.2.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum, Default,
)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// Alternate radiance and antiradiance propagation (eqs. 13 and 14 in lockstep).
    #[default]
    Symmetric,
    /// One radiance step, then several antiradiance steps with radiance frozen (provably converges).
    Asymmetric,
}
spelled!(
    Scheme,
    "scheme",
    [(Symmetric, "symmetric"), (Asymmetric, "asymmetric")]
);

impl Scheme {
    /// The other scheme (for sweeps and fallbacks).
    pub fn other(self) -> Self {
        match self {
            Scheme::Symmetric => Scheme::Asymmetric,
            Scheme::Asymmetric => Scheme::Symmetric,
        }
    }
}

/// Storage precision of the solver's tables: the GPU's float16 or float32 images, or the CPU
/// solver's f64 (reported, never requested).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum, Default,
)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// R16G16B16A16_SFLOAT (the paper's float16).
    #[default]
    F16,
    /// R32G32B32A32_SFLOAT.
    F32,
    /// The CPU solver's f64 tables (what a CPU result reports; not a GPU choice).
    #[value(skip)]
    F64,
}
impl Precision {
    /// Unit roundoff of the format (half its spacing at 1): the relative change per iteration
    /// below which the tables cannot resolve further progress.
    pub fn unit_roundoff(self) -> f64 {
        match self {
            Self::F16 => 2f64.powi(-11),
            Self::F32 => 2f64.powi(-24),
            Self::F64 => 2f64.powi(-53),
        }
    }
}

spelled!(
    Precision,
    "precision",
    [(F16, "f16"), (F32, "f32"), (F64, "f64")]
);

impl Precision {
    /// The other GPU precision (for sweeps).
    pub fn other(self) -> Self {
        match self {
            Precision::F16 => Precision::F32,
            _ => Precision::F16,
        }
    }
}

/// Which implementation solves and draws the frame.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum, Default,
)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// Vulkan raster passes (§4).
    #[default]
    Gpu,
    /// The f64 CPU solver and a ray-cast frame: the reference the GPU is checked against.
    Cpu,
}
spelled!(BackendKind, "backend", [(Gpu, "gpu"), (Cpu, "cpu")]);

/// How global illumination is computed: the paper's method, or a related system measured on
/// the same scene, frame formation and engine (each is a backend of [`crate::Engine`]).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum, Default,
)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Implicit visibility with antiradiance (the paper).
    #[default]
    Antiradiance,
    /// Hierarchical radiosity with clustering on the same links, each given a visibility
    /// fraction by rays, solved without antiradiance (the paper's Fig. 14f).
    HierarchicalRadiosity,
    /// Progressive refinement radiosity (Coombe and Harris, GPU Gems 2 ch. 39): the element
    /// with the most unshot energy shoots, visibility from a hemicube item buffer.
    ProgressiveRadiosity,
    /// Instant radiosity (Keller 1997): virtual point lights traced from the lights, gathered
    /// per pixel through their shadow maps.
    InstantRadiosity,
    /// The image-based radiosity representation: instant radiosity's VPLs accumulated through
    /// hemicubes into a view-independent layered depth cube, read per pixel.
    ImageBasedRadiosity,
}
spelled!(
    Method,
    "method",
    [
        (Antiradiance, "antiradiance"),
        (HierarchicalRadiosity, "hierarchical-radiosity"),
        (ProgressiveRadiosity, "progressive-radiosity"),
        (InstantRadiosity, "instant-radiosity"),
        (ImageBasedRadiosity, "image-based-radiosity")
    ]
);

impl Method {
    /// Every method, in the order reports list them.
    pub const ALL: [Method; 5] = [
        Method::Antiradiance,
        Method::HierarchicalRadiosity,
        Method::ProgressiveRadiosity,
        Method::InstantRadiosity,
        Method::ImageBasedRadiosity,
    ];

    /// Whether the method solves on the links (progressive refinement computes its form
    /// factors per shot, instant radiosity traces paths: neither needs links, so linking is
    /// skipped).
    pub fn uses_links(self) -> bool {
        !matches!(
            self,
            Method::ProgressiveRadiosity | Method::InstantRadiosity | Method::ImageBasedRadiosity
        )
    }

    /// Whether area emitters' direct light may come from shadow-mapped samples (§3.3).
    /// Progressive refinement shoots its emitters instead: that is the method's own way, and
    /// drawing samples per pixel as well would count their light twice.
    pub fn samples_emitters(self) -> bool {
        self != Method::ProgressiveRadiosity
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_spelling_everywhere() {
        for s in [Scheme::Symmetric, Scheme::Asymmetric] {
            assert_eq!(s.to_string().parse::<Scheme>(), Ok(s));
            assert_eq!(serde_json::to_string(&s).unwrap(), format!("\"{s}\""));
            let v = <Scheme as clap::ValueEnum>::to_possible_value(&s).unwrap();
            assert_eq!(v.get_name(), s.as_str());
        }
        for p in [Precision::F16, Precision::F32, Precision::F64] {
            assert_eq!(p.to_string().parse::<Precision>(), Ok(p));
            assert_eq!(serde_json::to_string(&p).unwrap(), format!("\"{p}\""));
        }
        for b in [BackendKind::Gpu, BackendKind::Cpu] {
            assert_eq!(b.to_string().parse::<BackendKind>(), Ok(b));
            assert_eq!(serde_json::to_string(&b).unwrap(), format!("\"{b}\""));
        }
        for m in Method::ALL {
            assert_eq!(m.to_string().parse::<Method>(), Ok(m));
            assert_eq!(serde_json::to_string(&m).unwrap(), format!("\"{m}\""));
            let v = <Method as clap::ValueEnum>::to_possible_value(&m).unwrap();
            assert_eq!(v.get_name(), m.as_str());
        }
        // f64 is reported, not offered on the command line.
        let names: Vec<_> = <Precision as clap::ValueEnum>::value_variants()
            .iter()
            .filter_map(|p| clap::ValueEnum::to_possible_value(p).map(|v| v.get_name().to_string()))
            .collect();
        assert_eq!(names, ["f16", "f32"]);
        assert_eq!(
            "f8".parse::<Precision>().unwrap_err(),
            r#"precision must be "f16" or "f32" or "f64", got "f8""#
        );
    }
}
