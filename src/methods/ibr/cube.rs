//! The layered depth cube (LDC) of the image-based radiosity representation: three layered depth
//! images (LDIs) over the scene's bounds, one per axis, of square cells. A sample goes to the
//! LDI whose axis is most parallel to its normal; in its cell it merges with a layer whose plane
//! it lies on (`|p·n − d| < ε_d` and `n′·n > 1 − ε_n`, the paper's §3.1 plane test), or opens a
//! new layer. Pure, device-free: both backends warp their hemicube samples through it.

use glam::DVec3;

/// Plane distance of the merge test, in cells (the paper's ε on `|p·n − d|`).
pub const PLANE_EPSILON_CELLS: f64 = 0.5;
/// Orientation part of the merge test: normals within about 25° share a layer.
pub const NORMAL_EPSILON: f64 = 0.1;
/// Most layers one cell keeps (a sample that would open another is dropped and counted).
pub const MAX_LAYERS: usize = 32;

/// One layer of a cell: a plane and the irradiance accumulated on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer {
    /// Unit normal of the plane (the first sample's).
    pub normal: DVec3,
    /// `p · normal` of the first sample.
    pub d: f64,
    /// Irradiance (W/m² per channel) summed over the virtual lights.
    pub irradiance: DVec3,
    /// The first sample's point: where the layer's direct light and near field are evaluated
    /// ([`super::near`]).
    pub point: DVec3,
    /// The direct light's irradiance at `point` (only [`super::near`] reads it: the frame
    /// computes its own per pixel).
    pub direct: DVec3,
    /// The irradiance the VPLs' clamp left out of their near field, restored by
    /// [`super::near::restore`] (zero until then).
    pub near: DVec3,
    /// The current light's samples in this layer: their sum, their count, and whether they are
    /// the light's own samples (1) or splatted copies (2); 0 where the light has none.
    sum: DVec3,
    count: u32,
    kind: u8,
}

/// Which of a light's samples is being inserted: its own hemicube texels, or the neighbouring
/// copies that splat them (which never add to a cell the light's own samples reached).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Insert {
    /// A texel's own sample.
    Own,
    /// A splatted copy of one, in a neighbouring cell.
    Copy,
}

/// The cube.
#[derive(Debug, Clone)]
pub struct Cube {
    /// Lower corner of the bounds.
    pub lo: DVec3,
    /// Side of a cell (the bounds' longest side over the resolution).
    pub cell: f64,
    /// Cells per axis of the bounds.
    pub dims: [usize; 3],
    /// Per LDI (axis 0, 1, 2), per cell (row-major over the two other axes), its layers.
    ldis: [Vec<Vec<Layer>>; 3],
    /// Per LDI, the layers the current light touched: (cell, layer).
    touched: [Vec<(u32, u16)>; 3],
    /// Per LDI, samples dropped because their cell was full.
    dropped: [u64; 3],
}

/// The two image axes of the LDI along `axis`.
pub fn image_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// The LDI a normal belongs to: the axis it is most parallel to.
pub fn axis_of(n: DVec3) -> usize {
    let a = n.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

/// Where the cells lie: what every LDI shares.
#[derive(Debug, Clone, Copy)]
struct Grid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
}

impl Grid {
    fn coords(&self, axis: usize, p: DVec3) -> (f64, f64) {
        let (b, c) = image_axes(axis);
        (
            (p[b] - self.lo[b]) / self.cell,
            (p[c] - self.lo[c]) / self.cell,
        )
    }

    fn index(&self, axis: usize, u: i64, v: i64) -> Option<usize> {
        let (b, c) = image_axes(axis);
        let (nu, nv) = (self.dims[b] as i64, self.dims[c] as i64);
        ((0..nu).contains(&u) && (0..nv).contains(&v)).then(|| (v * nu + u) as usize)
    }

    fn find(&self, layers: &[Layer], p: DVec3, n: DVec3) -> Option<usize> {
        let eps = PLANE_EPSILON_CELLS * self.cell;
        layers.iter().position(|l| {
            (p.dot(l.normal) - l.d).abs() < eps && n.dot(l.normal) > 1.0 - NORMAL_EPSILON
        })
    }
}

/// One LDI of a cube, borrowed on its own: the three take a light's samples in parallel.
pub struct Ldi<'a> {
    grid: Grid,
    axis: usize,
    cells: &'a mut [Vec<Layer>],
    touched: &'a mut Vec<(u32, u16)>,
    dropped: &'a mut u64,
}

impl Ldi<'_> {
    /// The axis of this LDI.
    pub fn axis(&self) -> usize {
        self.axis
    }

    /// [`Cube::insert`] for a sample whose normal is this LDI's.
    pub fn insert(&mut self, p: DVec3, n: DVec3, e: DVec3, kind: Insert, du: i64, dv: i64) {
        let (u, v) = self.grid.coords(self.axis, p);
        let Some(cell) = self
            .grid
            .index(self.axis, u.floor() as i64 + du, v.floor() as i64 + dv)
        else {
            return;
        };
        let want = if kind == Insert::Own { 1 } else { 2 };
        let layers = &mut self.cells[cell];
        let layer = match self.grid.find(layers, p, n) {
            Some(k) => k,
            None => {
                if layers.len() >= MAX_LAYERS {
                    *self.dropped += 1;
                    return;
                }
                layers.push(Layer {
                    normal: n,
                    d: p.dot(n),
                    irradiance: DVec3::ZERO,
                    point: p,
                    direct: DVec3::ZERO,
                    near: DVec3::ZERO,
                    sum: DVec3::ZERO,
                    count: 0,
                    kind: 0,
                });
                layers.len() - 1
            }
        };
        let l = &mut layers[layer];
        if l.kind == 0 {
            l.kind = want;
            self.touched.push((cell as u32, layer as u16));
        } else if l.kind != want {
            // Own samples replace copies; copies never add to own samples.
            if want == 2 {
                return;
            }
            l.kind = 1;
            l.sum = DVec3::ZERO;
            l.count = 0;
        }
        l.sum += e;
        l.count += 1;
    }

    /// [`Cube::finish_light`] for this LDI.
    pub fn finish_light(&mut self) {
        for (cell, layer) in self.touched.drain(..) {
            let l = &mut self.cells[cell as usize][layer as usize];
            l.irradiance += l.sum / l.count.max(1) as f64;
            l.sum = DVec3::ZERO;
            l.count = 0;
            l.kind = 0;
        }
    }
}

impl Cube {
    /// An empty cube over the box `lo..hi` with `resolution` cells along its longest side.
    pub fn new(lo: DVec3, hi: DVec3, resolution: usize) -> Self {
        let ext = (hi - lo).max(DVec3::splat(1e-9));
        let cell = ext.max_element() / resolution.max(1) as f64;
        // The cells' edges on the bounds' faces (a room's walls bound whole cells, not slivers
        // that a light's samples may miss), a hair of margin keeping samples on them inside.
        let lo = lo - DVec3::splat(1e-4 * cell);
        let dims = [0, 1, 2].map(|a| ((ext[a] / cell).ceil() as usize + 1).max(1));
        let cells = |axis: usize| {
            let (b, c) = image_axes(axis);
            dims[b] * dims[c]
        };
        Self {
            lo,
            cell,
            dims,
            ldis: [0, 1, 2].map(|a| vec![Vec::new(); cells(a)]),
            touched: Default::default(),
            dropped: [0; 3],
        }
    }

    fn grid(&self) -> Grid {
        Grid {
            lo: self.lo,
            cell: self.cell,
            dims: self.dims,
        }
    }

    /// Continuous cell coordinates of `p` in the LDI along `axis` (cell centres at k + 0.5).
    pub fn coords(&self, axis: usize, p: DVec3) -> (f64, f64) {
        self.grid().coords(axis, p)
    }

    /// The three LDIs, each borrowed on its own.
    pub fn ldis_mut(&mut self) -> [Ldi<'_>; 3] {
        let grid = self.grid();
        let [c0, c1, c2] = &mut self.ldis;
        let [t0, t1, t2] = &mut self.touched;
        let [d0, d1, d2] = &mut self.dropped;
        [(0, c0, t0, d0), (1, c1, t1, d1), (2, c2, t2, d2)].map(
            |(axis, cells, touched, dropped)| Ldi {
                grid,
                axis,
                cells,
                touched,
                dropped,
            },
        )
    }

    /// Adds one sample of the current light: irradiance `e` at `p` (unit normal `n`), into its
    /// own cell or, for a splatted copy, into cell (`du`, `dv`) away. A light's samples that
    /// meet in one layer are averaged (a hemicube that oversamples a cell counts it once), and
    /// copies never add where the light's own samples are.
    pub fn insert(&mut self, p: DVec3, n: DVec3, e: DVec3, kind: Insert, du: i64, dv: i64) {
        let axis = axis_of(n);
        let [a, b, c] = self.ldis_mut();
        [a, b, c]
            .into_iter()
            .nth(axis)
            .unwrap()
            .insert(p, n, e, kind, du, dv);
    }

    /// Ends the current light: every layer it reached takes the mean of its samples there.
    pub fn finish_light(&mut self) {
        for mut l in self.ldis_mut() {
            l.finish_light();
        }
    }

    /// Samples dropped because their cell was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.iter().sum()
    }

    /// The indirect irradiance at `p` (unit normal `n`): the VPLs' and their restored near
    /// field's, by [`Cube::lookup`].
    pub fn irradiance(&self, p: DVec3, n: DVec3) -> DVec3 {
        self.lookup(p, n, |l| l.irradiance + l.near)
    }

    /// `value` of the layers at `p` (unit normal `n`): the LDI of `n`, the 2×2 cells nearest
    /// `p` weighted bilinearly (the paper's averaging kernel), each where it has a layer on
    /// `p`'s plane; zero where none has.
    pub fn lookup(&self, p: DVec3, n: DVec3, value: impl Fn(&Layer) -> DVec3) -> DVec3 {
        let axis = axis_of(n);
        let grid = self.grid();
        let (u, v) = grid.coords(axis, p);
        let (u, v) = (u - 0.5, v - 0.5);
        let (u0, v0) = (u.floor(), v.floor());
        let (fu, fv) = (u - u0, v - v0);
        let (mut sum, mut wsum) = (DVec3::ZERO, 0.0);
        for (du, dv, w) in [
            (0, 0, (1.0 - fu) * (1.0 - fv)),
            (1, 0, fu * (1.0 - fv)),
            (0, 1, (1.0 - fu) * fv),
            (1, 1, fu * fv),
        ] {
            if w <= 0.0 {
                continue;
            }
            let Some(cell) = grid.index(axis, u0 as i64 + du, v0 as i64 + dv) else {
                continue;
            };
            if let Some(k) = grid.find(&self.ldis[axis][cell], p, n) {
                sum += value(&self.ldis[axis][cell][k]) * w;
                wsum += w;
            }
        }
        if wsum > 0.0 {
            sum / wsum
        } else {
            DVec3::ZERO
        }
    }

    /// Every layer, in a fixed order (LDI, cell, layer).
    pub fn layers_iter(&self) -> impl Iterator<Item = &Layer> {
        self.ldis.iter().flatten().flatten()
    }

    /// Sets every layer, in [`Cube::layers_iter`]'s order, from `values`.
    pub fn set_layers(&mut self, values: &[DVec3], mut set: impl FnMut(&mut Layer, DVec3)) {
        for (l, &v) in self.ldis.iter_mut().flatten().flatten().zip(values) {
            set(l, v);
        }
    }

    /// Layers over all cells (the paper's size: LDC pixels).
    pub fn layers(&self) -> usize {
        self.ldis.iter().flatten().map(Vec::len).sum()
    }

    /// Cells of the three LDIs together.
    pub fn cells(&self) -> usize {
        self.ldis.iter().map(Vec::len).sum()
    }

    /// Bytes the cube would take packed for a GPU: per layer a plane and an irradiance (8
    /// floats), per cell an offset and a count.
    pub fn bytes(&self) -> u64 {
        self.layers() as u64 * 32 + self.cells() as u64 * 8
    }

    /// Largest difference between two cubes' layers, relative to the larger irradiance of the
    /// two, over layers both have (matched by cell and plane), and the fraction of layers of
    /// either that the other lacks.
    pub fn compare(&self, other: &Cube) -> (f64, f64) {
        let (mut worst, mut missing, mut total) = (0.0f64, 0usize, 0usize);
        let peak = self
            .ldis
            .iter()
            .flatten()
            .flatten()
            .map(|l| l.irradiance.max_element())
            .fold(0.0f64, f64::max)
            .max(1e-300);
        for axis in 0..3 {
            for (a, b) in self.ldis[axis].iter().zip(&other.ldis[axis]) {
                total += a.len().max(b.len());
                for la in a {
                    let p = la.normal * la.d;
                    match b.iter().find(|lb| {
                        (p.dot(lb.normal) - lb.d).abs() < PLANE_EPSILON_CELLS * self.cell
                            && la.normal.dot(lb.normal) > 1.0 - NORMAL_EPSILON
                    }) {
                        Some(lb) => {
                            worst = worst
                                .max((la.irradiance - lb.irradiance).abs().max_element() / peak)
                        }
                        None => missing += 1,
                    }
                }
            }
        }
        (worst, missing as f64 / total.max(1) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Cube {
        Cube::new(DVec3::ZERO, DVec3::ONE, 8)
    }

    #[test]
    fn samples_of_one_light_average_and_lights_add() {
        let mut c = cube();
        let n = DVec3::Y;
        // Two samples of one light in one cell: their mean.
        c.insert(
            DVec3::new(0.51, 0.2, 0.51),
            n,
            DVec3::splat(1.0),
            Insert::Own,
            0,
            0,
        );
        c.insert(
            DVec3::new(0.52, 0.2, 0.52),
            n,
            DVec3::splat(3.0),
            Insert::Own,
            0,
            0,
        );
        c.finish_light();
        // A second light adds.
        c.insert(
            DVec3::new(0.51, 0.2, 0.51),
            n,
            DVec3::splat(4.0),
            Insert::Own,
            0,
            0,
        );
        c.finish_light();
        assert_eq!(c.layers(), 1);
        let p = DVec3::new(0.5625, 0.2, 0.5625); // the cell's centre: no neighbour weighs
        assert!((c.irradiance(p, n) - DVec3::splat(6.0)).length() < 1e-12);
    }

    #[test]
    fn planes_apart_open_layers_and_lookups_take_their_own() {
        let mut c = cube();
        // A floor and a shelf above it in the same column of the y LDI, and the shelf's
        // underside facing down.
        let (floor, shelf) = (DVec3::new(0.5, 0.0, 0.5), DVec3::new(0.5, 0.5, 0.5));
        c.insert(floor, DVec3::Y, DVec3::splat(1.0), Insert::Own, 0, 0);
        c.insert(shelf, DVec3::Y, DVec3::splat(2.0), Insert::Own, 0, 0);
        c.insert(shelf, -DVec3::Y, DVec3::splat(5.0), Insert::Own, 0, 0);
        c.finish_light();
        assert_eq!(c.layers(), 3);
        assert_eq!(c.irradiance(floor, DVec3::Y), DVec3::splat(1.0));
        assert_eq!(c.irradiance(shelf, DVec3::Y), DVec3::splat(2.0));
        assert_eq!(c.irradiance(shelf, -DVec3::Y), DVec3::splat(5.0));
        // A wall's sample goes to the x LDI; nothing there on the floor's plane.
        assert_eq!(
            c.irradiance(DVec3::new(0.5, 0.3, 0.5), DVec3::X),
            DVec3::ZERO
        );
    }

    #[test]
    fn copies_fill_gaps_but_never_add_to_own_samples() {
        let mut c = cube();
        let n = DVec3::Z;
        let p = DVec3::new(0.3, 0.3, 0.0);
        c.insert(p, n, DVec3::splat(2.0), Insert::Own, 0, 0);
        c.insert(
            p + DVec3::X * c.cell,
            n,
            DVec3::splat(4.0),
            Insert::Own,
            0,
            0,
        );
        // The first sample's copy into the next cell is ignored; into the one before, kept.
        c.insert(p, n, DVec3::splat(2.0), Insert::Copy, 1, 0);
        c.insert(p, n, DVec3::splat(2.0), Insert::Copy, -1, 0);
        c.finish_light();
        let at = |k: f64| c.irradiance(p + DVec3::X * (k * c.cell), n);
        assert_eq!(c.layers(), 3);
        // Along the row the values run 2 (copy), 2 (own), 4 (own), whatever the filter.
        for k in [-1.0, 0.0, 1.0] {
            let e = at(k).x;
            assert!((2.0..=4.0).contains(&e), "{k}: {e}");
        }
    }

    #[test]
    fn axis_is_the_most_parallel() {
        assert_eq!(axis_of(DVec3::new(0.1, -0.9, 0.2)), 1);
        assert_eq!(axis_of(DVec3::new(-0.7, 0.1, 0.7)), 0);
        assert_eq!(axis_of(DVec3::new(0.0, 0.1, -0.99)), 2);
    }
}
