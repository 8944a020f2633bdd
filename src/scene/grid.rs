//! Voxel grids as Mitsuba 3's `gridvolume` plugin reads and looks them up (src/volumes/grid.cpp,
//! src/render/volumegrid.cpp, and Dr.Jit's texture lookup, drjit/texture_impl.h's `tex_eval`
//! and `tex_wrap`, which the plugin's `Texture3f` evaluates with). A [`Grid`] is the CPU copy of
//! a `.vol` file (read by the loaders' `vol` module) that the renderer uploads; its lookups here are what
//! the GPU's are checked against.
//!
//! Conventions, as Mitsuba 3 has them:
//!
//! - **Where the grid lies.** The grid fills the unit cube [0, 1]^3 of the volume's local space;
//!   the volume's `to_world` places that cube in the world (a world point `p` is looked up at
//!   `to_world^-1 * p`). The bounding box stored in the file is *not* used unless the plugin's
//!   `use_grid_bbox` is true (default false); then the box is what the unit cube is stretched
//!   onto before `to_world`: local = (`to_world^-1 * p` - min) / (max - min)
//!   ([`Grid::bbox_transform`]). Mitsuba 0.6 placed grids by their box; Mitsuba 3 does not.
//! - **Cell-centred samples.** Value (i, j, k) sits at the centre of its cell,
//!   ((i + 0.5) / xres, (j + 0.5) / yres, (k + 0.5) / zres). Trilinear lookups interpolate between
//!   the centres; within half a cell of a face (and beyond) the wrap mode decides the
//!   neighbour, so with the default `clamp` the value is constant there, equal to the outer
//!   cells'.
//! - **Memory order.** x fastest, then y, then z, channels interleaved per cell:
//!   `data[((z * yres + y) * xres + x) * channels + c]`.
//! - **Filters and wrap modes.** `filter_type` is `trilinear` (default) or `nearest`;
//!   `wrap_mode` is `clamp` (default), `repeat` or `mirror`. They are the plugin's properties,
//!   not the file's, so they are arguments here ([`Grid::eval_with`]).
//! - **`raw`** only matters to Mitsuba's spectral variants, which otherwise turn a 3-channel
//!   grid's RGB into spectra (and then report a `max` of twice the largest channel of a cell);
//!   in its RGB variants, which the renderer follows, 3 channels are returned as they are.

use glam::{Mat4, Vec3};

/// How a lookup between cell centres is filtered (Mitsuba's `filter_type`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum FilterType {
    /// Trilinear interpolation of the eight nearest cell centres (Mitsuba's default).
    #[default]
    Trilinear,
    /// The value of the cell the point lies in.
    Nearest,
}

/// What a lookup reads past the grid's faces (Mitsuba's `wrap_mode`), applied to each integer
/// cell index a lookup touches.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum WrapMode {
    /// The nearest edge cell (Mitsuba's default).
    #[default]
    Clamp,
    /// The grid tiled periodically.
    Repeat,
    /// The grid reflected at its faces (index -1 reads cell 0, index `res` reads `res - 1`).
    Mirror,
}

/// A voxel grid of 1 or 3 channels, as read from a Mitsuba `.vol` file. The loader guarantees
/// `data.len() == size[0] * size[1] * size[2] * channels`, every size at least 1 and `channels`
/// 1 or 3; the lookups index `data` by those (and panic on a grid built by hand that breaks
/// them: [`Grid::check`] says whether one does).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Cells along x, y and z.
    pub size: [u32; 3],
    /// Values per cell: 1 (a scalar such as density) or 3 (RGB).
    pub channels: u32,
    /// The values, x fastest, then y, then z, channels interleaved per cell (see [`Grid::index`]).
    pub data: Vec<f32>,
    /// The bounding box the file states. Mitsuba 3 ignores it unless `use_grid_bbox` is set (see
    /// the module's documentation and [`Grid::bbox_transform`]); it is kept as read, unchecked.
    pub bbox_min: Vec3,
    pub bbox_max: Vec3,
}

impl Grid {
    /// A grid over the unit cube (the box Mitsuba gives grids it makes in memory).
    pub fn new(size: [u32; 3], channels: u32, data: Vec<f32>) -> Self {
        Grid {
            size,
            channels,
            data,
            bbox_min: Vec3::ZERO,
            bbox_max: Vec3::ONE,
        }
    }

    /// Number of cells (not values: times [`Grid::channels`] for those).
    pub fn cell_count(&self) -> u64 {
        self.size.iter().map(|&s| s as u64).product()
    }

    /// Whether the grid holds together: every size at least 1, 1 or 3 channels and as many
    /// values as cells times channels. The message says what is wrong.
    pub fn check(&self) -> Result<(), String> {
        if self.size.contains(&0) {
            return Err(format!(
                "resolution {}x{}x{} has an empty axis",
                self.size[0], self.size[1], self.size[2]
            ));
        }
        if self.channels != 1 && self.channels != 3 {
            return Err(format!("{} channels (1 or 3 are supported)", self.channels));
        }
        let expected = self.cell_count() as u128 * self.channels as u128;
        if self.data.len() as u128 != expected {
            return Err(format!(
                "{} values for {}x{}x{} cells of {} channel(s), which need {expected}",
                self.data.len(),
                self.size[0],
                self.size[1],
                self.size[2],
                self.channels
            ));
        }
        Ok(())
    }

    /// Index in [`Grid::data`] of channel 0 of cell (x, y, z):
    /// `((z * yres + y) * xres + x) * channels` (Mitsuba's layout, src/volumes/grid.cpp).
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        let [nx, ny, _] = self.size.map(|s| s as usize);
        ((z as usize * ny + y as usize) * nx + x as usize) * self.channels as usize
    }

    /// Cell (x, y, z)'s value: its three channels, or its one channel in all three components.
    pub fn cell(&self, x: u32, y: u32, z: u32) -> Vec3 {
        let i = self.index(x, y, z);
        if self.channels == 1 {
            Vec3::splat(self.data[i])
        } else {
            Vec3::new(self.data[i], self.data[i + 1], self.data[i + 2])
        }
    }

    /// The grid at `local`, a point of the unit cube [0, 1]^3 (the volume's local space: see the
    /// module's documentation), with Mitsuba's defaults: trilinear between cell centres, clamped
    /// at the faces. A 1-channel grid's value comes back in all three components (Mitsuba's
    /// `eval` in its RGB variants; its `eval_1` of such a grid is the same number).
    pub fn eval(&self, local: Vec3) -> Vec3 {
        self.eval_with(local, FilterType::Trilinear, WrapMode::Clamp)
    }

    /// The grid at `local` without interpolation (Mitsuba's `filter_type` `nearest`): the value of
    /// the cell `floor(local * size)` (clamped), i.e. of the cell `local` lies in.
    pub fn eval_nearest(&self, local: Vec3) -> Vec3 {
        self.eval_with(local, FilterType::Nearest, WrapMode::Clamp)
    }

    /// The grid at `local` with any `filter_type` and `wrap_mode`, computed as Dr.Jit's texture
    /// lookup computes it (drjit/texture_impl.h, `tex_eval`): along each axis the position in
    /// cells is `local * res - 0.5` for trilinear filtering (cell centres at whole numbers),
    /// `local * res` for nearest; its floor and the next index are wrapped one by one and the
    /// eight corners summed with weights `1 - f` and `f` of the fraction `f`.
    pub fn eval_with(&self, local: Vec3, filter: FilterType, wrap: WrapMode) -> Vec3 {
        let res = self.size.map(|s| s as i64);
        let p = local.to_array();
        if filter == FilterType::Nearest {
            let mut cell = [0u32; 3];
            for k in 0..3 {
                cell[k] = wrap_index(floor_index(p[k] * res[k] as f32), res[k], wrap);
            }
            return self.cell(cell[0], cell[1], cell[2]);
        }
        let mut lower = [0i64; 3];
        let mut weights = [[0f32; 2]; 3];
        for k in 0..3 {
            let pos = p[k].mul_add(res[k] as f32, -0.5);
            lower[k] = floor_index(pos);
            let f = pos - lower[k] as f32;
            weights[k] = [1.0 - f, f];
        }
        let mut out = Vec3::ZERO;
        for corner in 0..8 {
            let mut cell = [0u32; 3];
            let mut weight = 1.0f32;
            for k in 0..3 {
                let bit = (corner >> k) & 1;
                cell[k] = wrap_index(lower[k].saturating_add(bit as i64), res[k], wrap);
                weight *= weights[k][bit];
            }
            let v = self.cell(cell[0], cell[1], cell[2]);
            out = Vec3::new(
                v.x.mul_add(weight, out.x),
                v.y.mul_add(weight, out.y),
                v.z.mul_add(weight, out.z),
            );
        }
        out
    }

    /// The largest value over all cells and channels (Mitsuba's `max()` of a grid read from a
    /// file in its RGB variants, src/render/volumegrid.cpp: what a heterogeneous medium takes as
    /// its majorant, times its `scale`). `-inf` for a grid without values.
    pub fn max(&self) -> f32 {
        self.data.iter().copied().fold(f32::NEG_INFINITY, f32::max)
    }

    /// The largest value of each channel over all cells (Mitsuba's `max_per_channel`).
    pub fn max_per_channel(&self) -> Vec<f32> {
        let n = self.channels.max(1) as usize;
        let mut max = vec![f32::NEG_INFINITY; n];
        for (i, &v) in self.data.iter().enumerate() {
            max[i % n] = max[i % n].max(v);
        }
        max
    }

    /// The map from the volume's space onto the unit cube that Mitsuba's `use_grid_bbox` puts
    /// before the lookup (`VolumeGrid::bbox_transform`, include/mitsuba/render/volumegrid.h):
    /// scale by `1 / (max - min)` after translating by `-min`. With it a point `p` (after
    /// `to_world^-1`) is looked up at `bbox_transform() * p`. `None` when the file's box is not
    /// a box (a side not positive and finite, or a corner not finite), where Mitsuba's map would
    /// be infinite or not a number.
    pub fn bbox_transform(&self) -> Option<Mat4> {
        let extent = self.bbox_max - self.bbox_min;
        let usable = self.bbox_min.is_finite()
            && self.bbox_max.is_finite()
            && extent.cmpgt(Vec3::ZERO).all()
            && extent.recip().is_finite();
        usable.then(|| Mat4::from_scale(extent.recip()) * Mat4::from_translation(-self.bbox_min))
    }
}

/// `floor(x)` as an index; saturating for positions far beyond any grid (and 0 for NaN, whose
/// weights then make the lookup NaN).
fn floor_index(x: f32) -> i64 {
    x.floor() as i64
}

/// A cell index wrapped into `0..res` as Dr.Jit's `tex_wrap` does it (drjit/texture_impl.h).
fn wrap_index(i: i64, res: i64, wrap: WrapMode) -> u32 {
    let wrapped = match wrap {
        WrapMode::Clamp => i.clamp(0, res - 1),
        WrapMode::Repeat => i.rem_euclid(res),
        WrapMode::Mirror => {
            // The period (of length res) i falls in, and i's place in it; odd periods run
            // backwards.
            let period = i.div_euclid(res);
            let m = i.rem_euclid(res);
            if period.rem_euclid(2) == 0 {
                m
            } else {
                res - 1 - m
            }
        }
    };
    wrapped as u32
}
