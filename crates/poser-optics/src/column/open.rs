//! The column's light on an open plane: the irradiance that the column's diffuse radiance
//! (its binned table plus the sky's or the bottom's radiance through the water) puts on a
//! plane of any orientation at any depth with nothing in the way. The renderer's surfaces use
//! it as a control variate (docs/column.md, "Lighting the scene with it"): they add this
//! irradiance exactly and estimate by next-event estimation only what the local geometry
//! changes, so an unshaded point of a rough seabed carries no noise from the column's light.
//!
//! | function | meaning |
//! |---|---|
//! | [`Column::radiance_open`] | `h(z, ω)`: the binned table ([`Column::radiance_binned`]) plus the boundary's radiance through the water from the two layers' centres, with the table's depth weights |
//! | [`Column::irradiance_open`] | `∫ h(z, ω) max(0, n·ω) dω`, W/m² per channel: exact for the table's bins wholly above the plane's horizon (their vector solid-angle integrals), 8 × 8 sub-cells for bins the horizon cuts, and a 1D quadrature of closed-form azimuthal rings for the boundary; tabulated per layer on a grid of normals ([`NT`] × [`NP`] nodes in the sun's frame, bilinear), each layer when first used |
//!
//! The grid holds the two poles as nodes, so a level surface reads the exact integral; a
//! tilted one reads it interpolated over 2.5° × 5°, which errs by well under 0.1 % (the
//! irradiance is the radiance convolved with a clamped cosine: smooth;
//! `open_irradiance_integrates_the_open_radiance` checks it against brute-force quadrature).

use super::{Column, NMU, NPHI, NZ, mu_edge, polar, sky_seen};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Nodes in the polar angle of the normal, from the zenith (0) to the nadir (π): 2.5° apart.
pub const NT: usize = 73;
/// Nodes in the normal's azimuth from the sun, over [0, π] (the table is mirror-symmetric
/// about the sun's vertical plane): 5° apart.
pub const NP: usize = 37;
/// Nodes of the sampling grid of normals ([`Column::sample_open`]): polar 6° apart.
pub const ST: usize = 31;
/// Nodes of the sampling grid in the normal's azimuth from the sun, over [0, π]: 12° apart.
pub const SP: usize = 16;
/// Half-bins of the table: polar bin × signed azimuth over [−π, π] (the folded bins' two
/// mirror halves apart, as a tilted plane sees them unequally).
const HALVES: usize = NMU * 2 * NPHI;
/// Sub-cells per side of a bin that a plane's horizon cuts.
const SUB: usize = 8;
/// Points of the boundary's quadrature in cos θ.
const RING_POINTS: usize = 4096;

/// Per layer, the open irradiance at every node (`t · NP + p`), per channel; filled when a
/// layer is first read.
pub(super) type OpenLayers = Vec<OnceLock<Vec<[f64; 3]>>>;

pub(super) fn empty_layers() -> OpenLayers {
    (0..NZ).map(|_| OnceLock::new()).collect()
}

/// Per layer, for every node of the sampling grid (`t · SP + p`), the cumulative weights of
/// the [`HALVES`] half-bins (`HALVES + 1` entries from 0); filled when a layer is first read.
pub(super) type SampleLayers = Vec<OnceLock<Vec<f32>>>;

pub(super) fn empty_samplers() -> SampleLayers {
    (0..NZ).map(|_| OnceLock::new()).collect()
}

/// Polar bin and signed azimuth bounds of half-bin `h`.
fn half_bounds(h: usize) -> (usize, f64, f64) {
    let (i, js) = (h / (2 * NPHI), h % (2 * NPHI));
    let d = PI / NPHI as f64;
    let p = -PI + js as f64 * d;
    (i, p, p + d)
}

/// The folded bin (`i · NPHI + j`) holding half-bin `h`.
fn folded(h: usize) -> usize {
    let (i, js) = (h / (2 * NPHI), h % (2 * NPHI));
    let j = if js >= NPHI { js - NPHI } else { NPHI - 1 - js };
    i * NPHI + j
}

/// `∫ max(0, n·ω) dω` over every half-bin for every node of the sampling grid: index
/// `node · HALVES + h`. The same for every column; computed once.
fn half_cosines() -> &'static [f32] {
    static CELL: OnceLock<Vec<f32>> = OnceLock::new();
    CELL.get_or_init(|| {
        (0..ST * SP)
            .into_par_iter()
            .flat_map_iter(|node| {
                let n = grid_normal(node / SP, node % SP, ST, SP);
                half_bins().iter().map(move |hb| hb.cosine(n) as f32)
            })
            .collect()
    })
}

/// The normal of node `(t, p)` of a grid of `nt` polar × `np` azimuth nodes over [0, π]²,
/// in the sun's frame (x towards the sun's azimuth, z up).
pub(super) fn grid_normal(t: usize, p: usize, nt: usize, np: usize) -> DVec3 {
    let th = t as f64 * PI / (nt - 1) as f64;
    let ph = p as f64 * PI / (np - 1) as f64;
    DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
}

/// A look direction in the sun's frame at polar angle `a` from the nadir and azimuth `f`.
fn look(a: f64, f: f64) -> DVec3 {
    DVec3::new(a.sin() * f.cos(), a.sin() * f.sin(), -a.cos())
}

/// What `∫ max(0, n·ω) dω` over one half of a folded bin needs, whatever the normal `n`:
/// computed once per half-bin (its angles' sines and cosines), so that a grid of normals
/// costs dot products, not trigonometry.
struct HalfBin {
    /// The centre's direction and the angular radius about it.
    c: DVec3,
    r: f64,
    /// `∫ω dω` over the half-bin (closed form).
    v: DVec3,
    /// The sub-cells' centre directions and their `d cos θ`, row by row ([`SUB`] × [`SUB`]).
    cells: Vec<(DVec3, f64)>,
    /// The azimuth's span.
    qp: f64,
}

impl HalfBin {
    /// Polar `[a, b]` from the nadir, azimuth `[p, q]` in the sun's frame.
    fn new(a: f64, b: f64, p: f64, q: f64) -> HalfBin {
        let (am, fm) = (0.5 * (a + b), 0.5 * (p + q));
        let c = look(am, fm);
        // The bin's angular radius about its centre: the farthest of its corners and edge
        // midpoints, with a margin for the latitude arcs' bulge.
        let r = [a, am, b]
            .iter()
            .flat_map(|&x| [p, fm, q].map(|y| look(x, y)))
            .map(|v| c.dot(v).clamp(-1.0, 1.0).acos())
            .fold(0.0, f64::max)
            * 1.1
            + 1e-9;
        let i2 = 0.5 * (b - a) - 0.25 * ((2.0 * b).sin() - (2.0 * a).sin());
        let v = DVec3::new(
            i2 * (q.sin() - p.sin()),
            i2 * (p.cos() - q.cos()),
            -0.5 * (b.sin().powi(2) - a.sin().powi(2)) * (q - p),
        );
        let mut cells = Vec::with_capacity(SUB * SUB);
        for i in 0..SUB {
            let (x0, x1) = (
                a + (b - a) * i as f64 / SUB as f64,
                a + (b - a) * (i + 1) as f64 / SUB as f64,
            );
            let dmu = x0.cos() - x1.cos();
            for j in 0..SUB {
                let f = p + (q - p) * (j as f64 + 0.5) / SUB as f64;
                cells.push((look(0.5 * (x0 + x1), f), dmu));
            }
        }
        HalfBin {
            c,
            r,
            v,
            cells,
            qp: q - p,
        }
    }

    /// `∫ max(0, n·ω) dω` over the half-bin: closed form when it is wholly above the plane's
    /// horizon, 0 wholly below, else summed over its sub-cells.
    fn cosine(&self, n: DVec3) -> f64 {
        let h = n.dot(self.c).clamp(-1.0, 1.0).asin();
        if h <= -self.r {
            return 0.0;
        }
        if h >= self.r {
            return n.dot(self.v).max(0.0);
        }
        let mut s = 0.0;
        for (w, dmu) in &self.cells {
            s += n.dot(*w).max(0.0) * dmu * self.qp / SUB as f64;
        }
        s
    }
}

/// Every half-bin's [`HalfBin`], index `h` as [`half_bounds`].
fn half_bins() -> &'static [HalfBin] {
    static CELL: OnceLock<Vec<HalfBin>> = OnceLock::new();
    CELL.get_or_init(|| {
        (0..HALVES)
            .into_par_iter()
            .map(|h| {
                let (i, p, q) = half_bounds(h);
                let (a, b) = (i as f64 * PI / NMU as f64, (i + 1) as f64 * PI / NMU as f64);
                HalfBin::new(a, b, p, q)
            })
            .collect()
    })
}

/// Every folded bin's two mirror halves, index `i · NPHI + j`: azimuth `[p, q]` and
/// `[−q, −p]` with `p = jπ/NPHI` (computed as the folded table's bins are).
fn folded_halves() -> &'static [[HalfBin; 2]] {
    static CELL: OnceLock<Vec<[HalfBin; 2]>> = OnceLock::new();
    CELL.get_or_init(|| {
        (0..NMU * NPHI)
            .into_par_iter()
            .map(|bin| {
                let (i, j) = (bin / NPHI, bin % NPHI);
                let (a, b) = (i as f64 * PI / NMU as f64, (i + 1) as f64 * PI / NMU as f64);
                let (p, q) = (
                    j as f64 * PI / NPHI as f64,
                    (j + 1) as f64 * PI / NPHI as f64,
                );
                [HalfBin::new(a, b, p, q), HalfBin::new(a, b, -q, -p)]
            })
            .collect()
    })
}

/// `∫ max(0, n·ω) dω` over every folded bin of the table (both mirror halves), for every node:
/// index `node · NMU·NPHI + bin`. The same for every column; computed once.
fn bin_cosines() -> &'static [f32] {
    static CELL: OnceLock<Vec<f32>> = OnceLock::new();
    CELL.get_or_init(|| {
        (0..NT * NP)
            .into_par_iter()
            .flat_map_iter(|node| {
                let n = grid_normal(node / NP, node % NP, NT, NP);
                folded_halves()
                    .iter()
                    .map(move |[u, l]| (u.cosine(n) + l.cosine(n)) as f32)
            })
            .collect()
    })
}

/// [`Column::grid_nodes`] for the sun's azimuth `a` (unit, horizontal).
pub(super) fn grid_nodes_at(a: DVec3, n: DVec3, nt: usize, np: usize) -> ([(usize, f64); 4], bool) {
    let y = n.dot(DVec3::new(-a.y, a.x, 0.0));
    let ft = (n.z.clamp(-1.0, 1.0).acos() / PI * (nt - 1) as f64).clamp(0.0, (nt - 1) as f64);
    let fp = (y.abs().atan2(n.dot(a)) / PI * (np - 1) as f64).clamp(0.0, (np - 1) as f64);
    let (t0, p0) = ((ft as usize).min(nt - 2), (fp as usize).min(np - 2));
    let (tt, tp) = (ft - t0 as f64, fp - p0 as f64);
    let nodes = [
        (t0 * np + p0, (1.0 - tt) * (1.0 - tp)),
        (t0 * np + p0 + 1, (1.0 - tt) * tp),
        ((t0 + 1) * np + p0, tt * (1.0 - tp)),
        ((t0 + 1) * np + p0 + 1, tt * tp),
    ];
    (nodes, y < 0.0)
}

/// `∫₀^{2π} max(0, a + b cos φ) dφ` for `b ≥ 0`.
fn ring(a: f64, b: f64) -> f64 {
    if a >= b {
        2.0 * PI * a
    } else if a <= -b {
        0.0
    } else {
        let f0 = (-a / b).clamp(-1.0, 1.0).acos();
        2.0 * (a * f0 + b * f0.sin())
    }
}

impl Column {
    /// The two layers whose centres bracket depth `z` and their weights, as the table is read
    /// ([`Column::radiance_binned`]): linear between the centres, extrapolated in the outer
    /// half-layers.
    pub(super) fn depth_weights(&self, z: f64) -> [(usize, f64); 2] {
        let dz = self.depth / NZ as f64;
        let fz = (z / dz - 0.5).clamp(-0.5, NZ as f64 - 0.5);
        let k0 = (fz.max(0.0) as usize).min(NZ - 2);
        let tz = fz - k0 as f64;
        [(k0, 1.0 - tz), (k0 + 1, tz)]
    }

    /// The boundary's radiance seen from layer `k`'s centre along a look of `cos θ = mu`,
    /// through the water: the sky above (through Snell's window under a reflecting surface),
    /// the bottom below.
    pub(super) fn boundary_from_layer(&self, k: usize, mu: f64) -> DVec3 {
        let z = (k as f64 + 0.5) * self.depth / NZ as f64;
        let (to, l) = if mu > 0.0 {
            (z, sky_seen(self.sky, self.window, mu))
        } else if mu < 0.0 {
            (self.depth - z, self.bottom)
        } else {
            return DVec3::ZERO;
        };
        l * (-self.sigma_t * (to / mu.abs())).exp()
    }

    /// `h(z, ω)`: the column's whole diffuse radiance at depth `z` looking along `look` with
    /// nothing in the way, as the surfaces' control variate reads it: the binned table plus
    /// the boundary through the water from the layers' centres, weighted as the table is.
    pub fn radiance_open(&self, z: f64, look: DVec3) -> DVec3 {
        self.binned_sum(z, look) + self.boundary_open(z, look.z)
    }

    /// The boundary's part of [`Column::radiance_open`] for a look of `cos θ = mu`: the sky's
    /// or the bottom's radiance through the water from the two layers' centres, weighted as
    /// the table is.
    pub fn boundary_open(&self, z: f64, mu: f64) -> DVec3 {
        let mut out = DVec3::ZERO;
        for (k, w) in self.depth_weights(z) {
            if w != 0.0 {
                out += w * self.boundary_from_layer(k, mu);
            }
        }
        out
    }

    /// `∫ h(z, ω) max(0, n·ω) dω` ([`Column::radiance_open`]): the irradiance on an open
    /// plane of unit normal `n` (world, z up) at depth `z`, per channel, W/m².
    pub fn irradiance_open(&self, z: f64, n: DVec3) -> DVec3 {
        let (nodes, _) = self.grid_nodes(n, NT, NP);
        let mut out = DVec3::ZERO;
        for (k, wk) in self.depth_weights(z) {
            if wk == 0.0 {
                continue;
            }
            let layer = self.open_layer(k);
            for (m, wm) in nodes {
                if wm != 0.0 {
                    out += wk * wm * DVec3::from_array(layer[m]);
                }
            }
        }
        out
    }

    /// The four nodes about unit normal `n` on a grid of `nt` polar × `np` folded-azimuth
    /// nodes in the sun's frame (index `t · np + p`), with their bilinear weights, and whether
    /// `n`'s azimuth is on the mirror side (directions drawn for it are then mirrored).
    fn grid_nodes(&self, n: DVec3, nt: usize, np: usize) -> ([(usize, f64); 4], bool) {
        grid_nodes_at(self.sun_azimuth, n, nt, np)
    }

    /// Sample a look direction for a surface of unit normal `n` at depth `z`, with density
    /// nearly ∝ the open radiance × max(0, n·ω) (the channels summed): a mixture over the two
    /// layers bracketing `z` and the four nodes of the normals' grid about `n` of each node's
    /// distribution over the table's half-bins (the half-bin's light × its clamped-cosine
    /// integral for the node's normal), uniform within the half-bin. Returns (direction,
    /// density per sr), or `None` where the drawn node is dark.
    pub fn sample_open(&self, z: f64, n: DVec3, u: [f64; 4]) -> Option<(DVec3, f64)> {
        let [u0, u1, u2, u3] = u;
        let [(k0, w0), (k1, _)] = self.layers_at(z);
        let (k, u0) = if u0 < w0 {
            (k0, u0 / w0)
        } else {
            (k1, ((u0 - w0) / (1.0 - w0)).min(1.0 - f64::EPSILON))
        };
        let (nodes, mirror) = self.grid_nodes(n, ST, SP);
        let mut node = None;
        let mut acc = 0.0;
        for (m, w) in nodes {
            if w > 0.0 && u0 < acc + w {
                node = Some(m);
                break;
            }
            acc += w;
        }
        let m = node.or_else(|| nodes.iter().rev().find(|(_, w)| *w > 0.0).map(|x| x.0))?;
        let cdf = &self.sample_layer(k)[m * (HALVES + 1)..(m + 1) * (HALVES + 1)];
        let total = *cdf.last()? as f64;
        if !(total > 0.0) {
            return None;
        }
        let x = (u1 * total) as f32;
        let h = cdf
            .partition_point(|&v| v <= x)
            .saturating_sub(1)
            .min(HALVES - 1);
        if cdf[h + 1] <= cdf[h] {
            return None;
        }
        let (i, p, q) = half_bounds(h);
        let cz = mu_edge(i) + u2 * (mu_edge(i + 1) - mu_edge(i));
        let phi = p + u3 * (q - p);
        let sz = (1.0 - cz * cz).max(0.0).sqrt();
        let a = self.sun_azimuth;
        let perp = DVec3::new(-a.y, a.x, 0.0);
        let sign = if mirror { -1.0 } else { 1.0 };
        let dir =
            (a * (sz * phi.cos()) + perp * (sign * sz * phi.sin()) + DVec3::Z * cz).normalize();
        // The density of the half-bin drawn (its coordinates are known: no angles to
        // recompute from the direction).
        let pdf = self.pdf_half(z, &nodes, h);
        (pdf > 0.0).then_some((dir, pdf))
    }

    /// Density (per sr) of [`Column::sample_open`] for a surface of normal `n` at depth `z`.
    pub fn pdf_open(&self, z: f64, n: DVec3, look: DVec3) -> f64 {
        let (nodes, mirror) = self.grid_nodes(n, ST, SP);
        let a = self.sun_azimuth;
        let perp = DVec3::new(-a.y, a.x, 0.0);
        let y = look.dot(perp) * if mirror { -1.0 } else { 1.0 };
        let phi = y.atan2(look.dot(a));
        let i = ((polar(look.z) / PI * NMU as f64) as usize).min(NMU - 1);
        let js = (((phi + PI) / (PI / NPHI as f64)) as usize).min(2 * NPHI - 1);
        self.pdf_half(z, &nodes, i * 2 * NPHI + js)
    }

    /// Density (per sr) of [`Column::sample_open`] in half-bin `h`, for the sampling grid's
    /// `nodes` about the surface's normal.
    fn pdf_half(&self, z: f64, nodes: &[(usize, f64); 4], h: usize) -> f64 {
        let i = h / (2 * NPHI);
        let omega = (mu_edge(i + 1) - mu_edge(i)) * (PI / NPHI as f64);
        self.layers_at(z)
            .iter()
            .filter(|(_, w)| *w > 0.0)
            .map(|&(k, wk)| {
                let layer = self.sample_layer(k);
                nodes
                    .iter()
                    .filter(|(_, w)| *w > 0.0)
                    .map(|&(m, wm)| {
                        let cdf = &layer[m * (HALVES + 1)..(m + 1) * (HALVES + 1)];
                        let total = cdf[HALVES] as f64;
                        if total > 0.0 {
                            wm * (cdf[h + 1] as f64 - cdf[h] as f64) / total
                        } else {
                            0.0
                        }
                    })
                    .sum::<f64>()
                    * wk
            })
            .sum::<f64>()
            / omega
    }

    fn sample_layer(&self, k: usize) -> &[f32] {
        self.samplers[k].get_or_init(|| {
            let cos = half_cosines();
            let base = k * NMU * NPHI;
            // The light of each half-bin, the channels summed: the table and the boundary
            // through the water at the bin's centre.
            let light: Vec<f64> = (0..HALVES)
                .map(|h| {
                    let b = folded(h);
                    let i = b / NPHI;
                    let mu = 0.5
                        * (-(i as f64 * PI / NMU as f64).cos()
                            - ((i + 1) as f64 * PI / NMU as f64).cos());
                    let t: f64 = (0..3)
                        .map(|c| (self.table[c][base + b] + self.first[c][base + b]) as f64)
                        .sum();
                    (t + self.boundary_from_layer(k, mu).element_sum()).max(0.0)
                })
                .collect();
            let mut out = Vec::with_capacity(ST * SP * (HALVES + 1));
            for node in 0..ST * SP {
                let row = &cos[node * HALVES..(node + 1) * HALVES];
                let mut acc = 0.0f64;
                out.push(0.0f32);
                for (l, &c) in light.iter().zip(row) {
                    acc += l * c as f64;
                    out.push(acc as f32);
                }
            }
            out
        })
    }

    fn open_layer(&self, k: usize) -> &[[f64; 3]] {
        self.open[k].get_or_init(|| {
            let cos = bin_cosines();
            let base = k * NMU * NPHI;
            let l: Vec<[f64; 3]> = (0..NMU * NPHI)
                .map(|b| {
                    [0, 1, 2].map(|c| (self.table[c][base + b] + self.first[c][base + b]) as f64)
                })
                .collect();
            // The boundary: azimuthally uniform, so a ring integral in closed form per cos θ.
            let ring_at = |nz: f64| {
                let sn = (1.0 - nz * nz).max(0.0).sqrt();
                let dmu = 2.0 / RING_POINTS as f64;
                (0..RING_POINTS).fold(DVec3::ZERO, |acc, i| {
                    let mu = -1.0 + (i as f64 + 0.5) * dmu;
                    let s = (1.0 - mu * mu).max(0.0).sqrt();
                    acc + self.boundary_from_layer(k, mu) * ring(nz * mu, sn * s) * dmu
                })
            };
            let rings: Vec<DVec3> = (0..NT)
                .map(|t| ring_at(grid_normal(t, 0, NT, NP).z))
                .collect();
            (0..NT * NP)
                .map(|node| {
                    let row = &cos[node * NMU * NPHI..(node + 1) * NMU * NPHI];
                    let mut e = rings[node / NP].to_array();
                    for (lb, &cb) in l.iter().zip(row) {
                        if cb != 0.0 {
                            for c in 0..3 {
                                e[c] += lb[c] * cb as f64;
                            }
                        }
                    }
                    e
                })
                .collect()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Top, reef_site, solve};
    use super::*;

    #[test]
    fn bins_integrate_the_clamped_cosine() {
        // Over the whole sphere, ∫ max(0, n·ω) dω = π for every normal.
        let cos = bin_cosines();
        for node in [0, 5, NP * 20 + 7, NP * 36 + 18, NP * 50 + 36, NT * NP - 1] {
            let s: f64 = cos[node * NMU * NPHI..(node + 1) * NMU * NPHI]
                .iter()
                .map(|&v| v as f64)
                .sum();
            assert!((s - PI).abs() < 2e-5 * PI, "node {node}: {s} against π");
        }
        // Level: exactly the upper half's projected solid angle.
        let up: f64 = cos[..NMU * NPHI].iter().map(|&v| v as f64).sum();
        assert!((up - PI).abs() < 1e-6);
    }

    #[test]
    fn rings_integrate_the_clamped_cosine() {
        for nz in [-1.0, -0.3, 0.0, 0.5, 0.9, 1.0] {
            let sn = (1.0f64 - nz * nz).sqrt();
            let n = 20000;
            let s: f64 = (0..n)
                .map(|i| {
                    let mu = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                    ring(nz * mu, sn * (1.0 - mu * mu).sqrt()) * 2.0 / n as f64
                })
                .sum();
            assert!((s - PI).abs() < 1e-4, "{nz}: {s}");
        }
    }

    /// The tabulated irradiance against a brute-force quadrature of the open radiance, at
    /// nodes and between them, under a sun and a sky through Snell's window with a bottom.
    #[test]
    fn open_irradiance_integrates_the_open_radiance() {
        let col = solve(&reef_site([1.0, 2.0, 3.0], Top::Fresnel([1.34; 3]), 20_000)).unwrap();
        // Sub-cells aligned with the bins, 16 per bin side, full azimuth.
        let (na, nf) = (NMU * 16, 2 * NPHI * 16);
        let brute = |z: f64, n: DVec3| {
            let mut e = DVec3::ZERO;
            for i in 0..na {
                let (a0, a1) = (i as f64 * PI / na as f64, (i + 1) as f64 * PI / na as f64);
                let dmu = a0.cos() - a1.cos();
                for j in 0..nf {
                    let f = (j as f64 + 0.5) * 2.0 * PI / nf as f64;
                    let w = look(0.5 * (a0 + a1), f);
                    let w = col.sun_azimuth * w.x
                        + DVec3::new(-col.sun_azimuth.y, col.sun_azimuth.x, 0.0) * w.y
                        + DVec3::Z * w.z;
                    let c = n.dot(w);
                    if c > 0.0 {
                        e += col.radiance_open(z, w) * c * dmu * 2.0 * PI / nf as f64;
                    }
                }
            }
            e
        };
        for (z, n) in [
            (11.9, DVec3::Z),
            (11.9, DVec3::new(0.3, 0.2, 0.9).normalize()),
            (6.3, DVec3::new(-0.7, 0.5, 0.2).normalize()),
            (9.0, DVec3::new(0.1, -0.6, -0.5).normalize()),
            (0.05, DVec3::new(0.2, 0.1, 0.97).normalize()),
        ] {
            let (got, want) = (col.irradiance_open(z, n), brute(z, n));
            for c in 0..3 {
                assert!(
                    (got[c] / want[c] - 1.0).abs() < 1e-3,
                    "z {z}, n {n}, channel {c}: {} against {}",
                    got[c],
                    want[c]
                );
            }
        }
    }

    /// The normal-aware sampler draws with the density it reports, covers every direction a
    /// tilted plane faces where there is light, and follows the open radiance × cosine closely:
    /// its one-direction estimate of the open irradiance averages to it with a small spread.
    #[test]
    fn open_sampling_follows_the_light_on_a_tilted_plane() {
        use crate::rng::SplitMix64;
        let col = solve(&reef_site([1.0, 2.0, 3.0], Top::Fresnel([1.34; 3]), 20_000)).unwrap();
        let mut rng = SplitMix64(3);
        for (z, n) in [
            (11.9, DVec3::Z),
            (11.6, DVec3::new(0.5, -0.3, 0.8).normalize()),
            (10.0, DVec3::new(-0.8, 0.1, 0.1).normalize()),
            (7.0, DVec3::new(0.2, 0.4, -0.6).normalize()),
        ] {
            let count = 40_000;
            let (mut s, mut s2, mut below) = (DVec3::ZERO, DVec3::ZERO, 0usize);
            for _ in 0..count {
                let u = [0, 1, 2, 3].map(|_| rng.next_f64());
                let Some((w, p)) = col.sample_open(z, n, u) else {
                    continue;
                };
                assert!((w.length() - 1.0).abs() < 1e-9);
                let q = col.pdf_open(z, n, w);
                assert!((p - q).abs() < 1e-9 * p, "{p} vs {q}");
                let e = col.radiance_open(z, w) * n.dot(w).max(0.0) / p;
                s += e;
                s2 += e * e;
                below += usize::from(n.dot(w) <= 0.0);
            }
            let m = s / count as f64;
            let want = col.irradiance_open(z, n);
            let spread = (s2 / count as f64 - m * m).max(DVec3::ZERO).sqrt() / m;
            for c in 0..3 {
                assert!(
                    (m[c] / want[c] - 1.0).abs() < 0.01,
                    "z {z}, n {n}, channel {c}: {} against {}",
                    m[c],
                    want[c]
                );
                // Red is dark at depth, and the channels' sum leads the draws.
                let most = if c == 0 { 1.0 } else { 0.3 };
                assert!(
                    spread[c] < most,
                    "z {z}, n {n}, channel {c}: spread {}",
                    spread[c]
                );
            }
            // Few draws are wasted below the plane's horizon (the nodes about `n` face a few
            // degrees otherwise).
            let wasted = below as f64 / count as f64;
            assert!(wasted < 0.05, "z {z}, n {n}: {wasted}");
        }
    }
}
