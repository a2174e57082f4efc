//! The ranges a scene's numbers must lie in, checked at load so that nothing out of range
//! reaches meshing, linking or a device. Each limit says what it protects.

use crate::elements::Element;
use crate::hierarchy::Node;

/// Default element size (when the scene file gives none) as a fraction of the scene's
/// bounding-box diagonal: the bundled Cornell box (diagonal 3.49) gets 0.25, the size its
/// settings were tuned at, and the same scene in any units gets the same elements.
pub const RELATIVE_ELEMENT_SIZE: f64 = 0.072;

/// Cap on `solver.iterations` and `solver.max_iterations`. Not a convergence limit (the
/// iteration converges in tens of steps): a count beyond it is a typo that would keep a GPU busy
/// for hours.
pub const MAX_ITERATIONS: usize = 100_000;

/// Cap on `solver.antiradiance_steps` (antiradiance steps per radiance step, default 4): each
/// step is a full global pass, and more than this never changes the fixed point.
pub const MAX_ANTIRADIANCE_STEPS: usize = 100;

/// Largest coordinate magnitude (vertex after its object's transform, camera, light position,
/// translation, scale factor, matrix entry): its square (areas, 1/r² form factors) must stay
/// far inside float32's range (3.4e38) in the GPU tables.
pub const MAX_COORDINATE: f64 = 1e15;

/// Largest emitted radiance (`Ke`, `environment.radiance`), light intensity (W/sr) or
/// irradiance (W/m²): multiplied by areas, 1/r² and the interreflection gain (up to 1e4), a
/// brighter source overflows float32 tables and images (3.4e38), and no power-of-two table
/// scale (at most 2^±120) brings it back into float16's range.
pub const MAX_SOURCE: f64 = 1e15;

/// `solver.element_size` must be at least this fraction of the largest coordinate magnitude:
/// bisection needs midpoints that float64 (52-bit mantissa) still tells apart from the ends,
/// with ~20 bits of margin.
pub const MIN_RELATIVE_RESOLUTION: f64 = 1e-9;

/// Host memory one leaf element takes at least: the element, its two hierarchy nodes and the
/// index lists. Links and tables come on top and are checked when the system is built.
pub const BYTES_PER_ELEMENT: usize =
    std::mem::size_of::<Element>() + 2 * std::mem::size_of::<Node>() + 3 * 4;

/// Host memory one link takes while linking and solving (the CPU record, its sorted copy, the
/// GPU record being packed), a budget for [`max_links_limit`].
pub const BYTES_PER_LINK: u64 = 96;

/// Most links the linker builds before it stops with an error: what this machine's memory
/// holds (a tiny `oracle` or element size refines without end otherwise).
pub fn max_links_limit() -> u64 {
    physical_memory_bytes().map_or(1 << 30, |b| b / BYTES_PER_LINK)
}

/// Rows are `u32` indices and a hierarchy has `2n − 1` of them.
const INDEX_LIMIT: usize = (u32::MAX / 2) as usize;

/// The most leaf elements this machine can hold: its physical memory over
/// [`BYTES_PER_ELEMENT`], and never more than the `u32` row indices can address.
pub fn max_elements_limit() -> usize {
    physical_memory_bytes().map_or(INDEX_LIMIT, |b| {
        ((b / BYTES_PER_ELEMENT as u64) as usize).min(INDEX_LIMIT)
    })
}

/// Total physical memory (Linux `/proc/meminfo`); `None` where it cannot be read.
pub fn physical_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: u64 = text
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_machine_limit_is_sane() {
        let n = max_elements_limit();
        assert!((1_000_000..=INDEX_LIMIT).contains(&n), "{n}");
        const { assert!(BYTES_PER_ELEMENT >= 200) };
    }
}
