//! A generated textured photogrammetric site: a coral bommie 0.7 m high on rubble, a 4 m × 4 m
//! height field of exactly N triangles in OBJ + MTL (`Kd 1 1 1`, `map_Kd model.jpg`) + an sRGB
//! JPEG of P² texels (quality 90), the way Metashape or OpenMVS export a model. Deterministic:
//! a fixed seed, nothing from the clock or the thread count, so the same sizes give the same
//! bytes on every machine. Two users: `poser bench mesh` (5 M triangles, 8192², written to a
//! temporary folder) and the shipped site `scenarios/sites/assets/textured_bommie/`
//! ([`SHIPPED_TRIANGLES`], [`SHIPPED_TEXTURE`]), which `poser bench mesh --site-only` rewrites
//! and a test regenerates byte for byte.
//!
//! The site's frame: x east, y north, z up, its base at z = 0 (the rubble's relief is about
//! ±5 cm around it); the texture's u runs west to east and v south to north over the whole
//! square, its west half warm and its east half cool (a boundary 6 cm wide at x = 0).

use std::io::Write;
use std::path::Path;

/// Half the site's side, m (the site is 4 m × 4 m, centred on the origin).
pub const HALF: f64 = 2.0;
/// The seed of every noise of the site.
pub const SEED: u64 = 36;
/// Triangles of the shipped site.
pub const SHIPPED_TRIANGLES: u64 = 32_000;
/// Side of the shipped site's texture, texels.
pub const SHIPPED_TEXTURE: u32 = 2048;
/// Where the shipped site lives, from the repository's root.
pub const SHIPPED_DIR: &str = "scenarios/sites/assets/textured_bommie";

/// SplitMix64's finaliser.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A lattice value in [−1, 1].
fn lattice(seed: u64, i: i64, j: i64) -> f64 {
    let h = mix(seed ^ mix((i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ mix(j as u64)));
    (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Value noise of feature `size` (m) in [−1, 1], smoothstep-interpolated.
fn noise(seed: u64, x: f64, y: f64, size: f64) -> f64 {
    let (x, y) = (x / size, y / size);
    let (i, j) = (x.floor(), y.floor());
    let (fx, fy) = (x - i, y - j);
    let s = |t: f64| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let (i, j) = (i as i64, j as i64);
    let a = lattice(seed, i, j) + sx * (lattice(seed, i + 1, j) - lattice(seed, i, j));
    let b = lattice(seed, i, j + 1) + sx * (lattice(seed, i + 1, j + 1) - lattice(seed, i, j + 1));
    a + sy * (b - a)
}

/// Height of the relief above the site's base at (x, y), m: a bommie 0.7 m high and about
/// 1.2 m across, its surface knobbly, on rubble.
pub fn height(x: f64, y: f64) -> f64 {
    let r2 = (x - 0.1).powi(2) + (y + 0.05).powi(2);
    let bommie = 0.7 * (-r2 / (2.0 * 0.6 * 0.6)).exp() * (1.0 + 0.15 * noise(SEED, x, y, 0.3));
    let rubble = 0.04 * noise(SEED + 1, x, y, 0.12) + 0.012 * noise(SEED + 2, x, y, 0.03);
    bommie + rubble
}

/// Linear albedo of the texture at (x, y): warm coral rubble west of x = 0, cool east of it
/// (a boundary 6 cm wide), mottled at every scale down to a few millimetres, with a texel
/// speckle `speck` in [−1, 1].
pub fn albedo(x: f64, y: f64, speck: f64) -> [f64; 3] {
    const WARM: [f64; 3] = [0.50, 0.30, 0.12];
    const COOL: [f64; 3] = [0.12, 0.30, 0.50];
    let t = ((x + 0.03) / 0.06).clamp(0.0, 1.0);
    let s = t * t * (3.0 - 2.0 * t);
    let mut m = 0.0;
    let mut amp = 1.0;
    let mut size = 0.2;
    for k in 0..5 {
        m += amp * noise(SEED + 10 + k, x, y, size);
        amp *= 0.7;
        size *= 0.4;
    }
    let f = (1.0 + 0.2 * m + 0.08 * speck).max(0.0);
    [0, 1, 2].map(|c| (WARM[c] + s * (COOL[c] - WARM[c])) * f)
}

/// What [`write`] wrote.
#[derive(Debug, Clone, Copy)]
pub struct Written {
    /// Vertices of the OBJ (the grid's).
    pub vertices: u64,
    pub obj_bytes: u64,
    pub image_bytes: u64,
}

/// The grid's cells: `a` columns by `b` rows, 2·a·b ≥ n triangles.
pub fn grid(n: u64) -> (u64, u64) {
    let a = ((n as f64 / 2.0).sqrt().ceil() as u64).max(1);
    (a, (n.div_ceil(2)).div_ceil(a))
}

/// Write `model.obj`, `model.mtl` and `model.jpg` into `dir` (created if missing): `triangles`
/// triangles (exactly) and a `texture`² JPEG. Each file goes to a temporary file beside it, then
/// is renamed. The bytes depend on nothing but the two sizes.
pub fn write(dir: &Path, triangles: u64, texture: u32) -> Result<Written, String> {
    if triangles < 2 || triangles > crate::geometry::meshfile::MAX_ELEMENTS as u64 {
        return Err(format!(
            "{triangles} triangles: between 2 and {}",
            crate::geometry::meshfile::MAX_ELEMENTS
        ));
    }
    if !(16..=crate::io::read::MAX_TEXTURE_SIDE).contains(&texture) {
        return Err(format!(
            "a {texture}² texture: its side between 16 and {}",
            crate::io::read::MAX_TEXTURE_SIDE
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let image_bytes = write_texture(&dir.join("model.jpg"), texture)?;
    let mtl = "# poser: a generated coral bommie (src/geometry/bommie.rs)\nnewmtl site\nKa 1 1 1\n\
               Kd 1 1 1\nKs 0 0 0\nillum 1\nmap_Kd model.jpg\n";
    crate::io::write_atomic(&dir.join("model.mtl"), mtl.as_bytes())
        .map_err(|e| format!("model.mtl: {e}"))?;
    // Streamed to a temporary file beside it, then renamed (the repo's one way to write).
    let mut counts = (0, 0);
    crate::io::write_atomic_with(&dir.join("model.obj"), |tmp| {
        counts = write_obj(tmp, triangles)?;
        Ok(())
    })?;
    let (vertices, obj_bytes) = counts;
    Ok(Written {
        vertices,
        obj_bytes,
        image_bytes,
    })
}

/// The height field as OBJ: every grid vertex (`v`, `vt`), then exactly `n` triangles, row by
/// row, in blocks formatted in parallel (the same bytes at any thread count). Returns the
/// vertices and bytes written.
fn write_obj(path: &Path, n: u64) -> Result<(u64, u64), String> {
    use rayon::prelude::*;
    let (a, b) = grid(n);
    let err = |e: std::io::Error| format!("{}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
    let mut bytes = 0u64;
    let head = format!(
        "# poser: a generated coral bommie, {n} triangles, a {a}×{b} height field (seed {SEED})\n\
         mtllib model.mtl\n"
    );
    out.write_all(head.as_bytes()).map_err(err)?;
    bytes += head.len() as u64;
    let xy = |i: u64, j: u64| {
        (
            -HALF + 2.0 * HALF * i as f64 / a as f64,
            -HALF + 2.0 * HALF * j as f64 / b as f64,
        )
    };
    const BLOCK: u64 = 64;
    let blocks: Vec<u64> = (0..=b).step_by(BLOCK as usize).collect();
    for pass in 0..2 {
        for chunk in blocks.chunks(8) {
            let texts: Vec<String> = chunk
                .par_iter()
                .map(|&j0| {
                    let mut s = String::new();
                    for j in j0..(j0 + BLOCK).min(b + 1) {
                        for i in 0..=a {
                            let (x, y) = xy(i, j);
                            if pass == 0 {
                                s += &format!("v {x:.6} {y:.6} {:.6}\n", height(x, y));
                            } else {
                                let (u, v) = ((x + HALF) / (2.0 * HALF), (y + HALF) / (2.0 * HALF));
                                s += &format!("vt {u:.6} {v:.6}\n");
                            }
                        }
                    }
                    s
                })
                .collect();
            for t in texts {
                out.write_all(t.as_bytes()).map_err(err)?;
                bytes += t.len() as u64;
            }
        }
    }
    out.write_all(b"usemtl site\n").map_err(err)?;
    bytes += 12;
    let rows: Vec<u64> = (0..b).step_by(BLOCK as usize).collect();
    for chunk in rows.chunks(8) {
        let texts: Vec<String> = chunk
            .par_iter()
            .map(|&j0| faces(j0, (j0 + BLOCK).min(b), a, n))
            .collect();
        for t in texts {
            out.write_all(t.as_bytes()).map_err(err)?;
            bytes += t.len() as u64;
        }
    }
    out.flush().map_err(err)?;
    Ok(((a + 1) * (b + 1), bytes))
}

/// The faces of cell rows `j0..j1` of an `a`-column grid (1-based OBJ indices, `v/vt` the
/// same), stopping at triangle `n`: counter-clockwise seen from above.
pub fn faces(j0: u64, j1: u64, a: u64, n: u64) -> String {
    let mut s = String::new();
    let id = |i: u64, j: u64| j * (a + 1) + i + 1;
    for j in j0..j1 {
        for i in 0..a {
            let k = 2 * (j * a + i);
            let (p, q, r, t) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if k < n {
                s += &format!("f {p}/{p} {q}/{q} {r}/{r}\n");
            }
            if k + 1 < n {
                s += &format!("f {p}/{p} {r}/{r} {t}/{t}\n");
            }
        }
    }
    s
}

/// The texture as a JPEG of `side`² sRGB texels (quality 90), north (y = +2 m) in the first
/// row. Returns its bytes.
fn write_texture(path: &Path, side: u32) -> Result<u64, String> {
    use rayon::prelude::*;
    let w = side as usize;
    let mut rgb = vec![0u8; 3 * w * w];
    rgb.par_chunks_mut(3 * w).enumerate().for_each(|(r, row)| {
        let y = HALF - 2.0 * HALF * (r as f64 + 0.5) / side as f64;
        for i in 0..w {
            let x = -HALF + 2.0 * HALF * (i as f64 + 0.5) / side as f64;
            let speck = lattice(SEED + 99, i as i64, r as i64);
            let c = albedo(x, y, speck);
            for ch in 0..3 {
                row[3 * i + ch] = crate::image::srgb8(c[ch]);
            }
        }
    });
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 90)
        .encode(&rgb, side, side, image::ExtendedColorType::Rgb8)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    drop(rgb);
    crate::io::write_atomic(path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(bytes.len() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_holds_the_triangles_asked_for() {
        for n in [2, 3, 20_000, 500_000, 5_000_000] {
            let (a, b) = grid(n);
            assert!(2 * a * b >= n && 2 * a * (b - 1) < n, "{n}: {a}×{b}");
        }
        let text = faces(0, 2, 3, 9);
        assert_eq!(text.lines().count(), 9);
        assert!(text.starts_with("f 1/1 2/2 6/6\nf 1/1 6/6 5/5\n"), "{text}");
    }

    #[test]
    fn the_site_is_deterministic_and_in_range() {
        assert_eq!(height(0.3, -0.2).to_bits(), height(0.3, -0.2).to_bits());
        for k in 0..100 {
            let (x, y) = (-2.0 + 0.04 * k as f64, 1.9 - 0.038 * k as f64);
            let h = height(x, y);
            assert!((-0.1..1.0).contains(&h), "{h}");
            let c = albedo(x, y, 1.0);
            assert!(c.iter().all(|v| (0.0..=1.0).contains(v)), "{c:?}");
        }
        // Red over blue is the base colours' whatever the mottling: warm west, cool east.
        let (w, e) = (albedo(-0.5, 0.3, 0.0), albedo(0.5, 0.3, 0.0));
        assert!((w[0] / w[2] - 0.50 / 0.12).abs() < 1e-9, "{w:?}");
        assert!((e[0] / e[2] - 0.12 / 0.50).abs() < 1e-9, "{e:?}");
    }

    /// The shipped site is what the generator writes at its sizes, byte for byte: the files in
    /// the repository and the code cannot drift apart (`poser bench mesh --site DIR` rewrites
    /// them).
    #[test]
    fn the_shipped_site_is_what_the_generator_writes() {
        let dir = tempfile::tempdir().unwrap();
        let w = write(dir.path(), SHIPPED_TRIANGLES, SHIPPED_TEXTURE).unwrap();
        let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join(SHIPPED_DIR);
        for name in ["model.obj", "model.mtl", "model.jpg"] {
            let a = std::fs::read(dir.path().join(name)).unwrap();
            let b = std::fs::read(shipped.join(name))
                .unwrap_or_else(|e| panic!("{}: {e}", shipped.join(name).display()));
            assert!(
                a == b,
                "{name}: the shipped file ({} bytes) is not what the generator writes ({} bytes): \
                 rerun `poser bench mesh --site {SHIPPED_DIR}`",
                b.len(),
                a.len()
            );
        }
        let obj = std::fs::read_to_string(dir.path().join("model.obj")).unwrap();
        let faces = obj.lines().filter(|l| l.starts_with("f ")).count() as u64;
        let vertices = obj.lines().filter(|l| l.starts_with("v ")).count() as u64;
        assert_eq!((faces, vertices), (SHIPPED_TRIANGLES, w.vertices));
        // Small enough to ship: under 3 MB together.
        assert!(w.obj_bytes + w.image_bytes < 3_000_000, "{w:?}");
    }

    #[test]
    fn sizes_out_of_range_are_refused_before_anything_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let e = write(&dir.path().join("a"), 1, 64).unwrap_err();
        assert!(e.contains("between 2 and"), "{e}");
        let e = write(&dir.path().join("b"), 100, 8).unwrap_err();
        assert!(e.contains("between 16 and"), "{e}");
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
    }
}
