//! The generator of `scenarios/assets/amphora.glb` (a lathe-turned amphora, 0.58 m tall, glTF
//! Y-up, metres) and its checks: the committed file is byte-identical to what this generator
//! writes, and it loads through `poser::geometry::mesh::load_gltf` standing upright along +z.
//!
//! Regenerate with `POSER_REGEN_ASSETS=1 cargo test --test suite native_amphora::`.

use serde_json::json;
use std::path::PathBuf;

const SEGMENTS: usize = 48;

/// Profile (height y, radius r) from the foot to the lip, metres.
fn profile() -> Vec<(f64, f64)> {
    let mut p = vec![(0.0, 0.045), (0.015, 0.05), (0.03, 0.04)];
    // Body: a smooth bulge from the foot up to the shoulder, then a neck and a rolled lip.
    let n = 24;
    for i in 0..=n {
        let s = i as f64 / n as f64; // 0..1 along the body
        let y = 0.04 + 0.40 * s;
        let bulge = (std::f64::consts::PI * s.powf(0.8)).sin();
        let r = 0.045 + 0.13 * bulge * (1.0 - 0.3 * s);
        p.push((y, r));
    }
    p.extend([
        (0.47, 0.045),
        (0.53, 0.042),
        (0.56, 0.06),
        (0.575, 0.062),
        (0.58, 0.05),
    ]);
    p
}

fn amphora_glb() -> Vec<u8> {
    let prof = profile();
    let mut pos: Vec<[f32; 3]> = Vec::new();
    // Bottom centre, rings, top centre (closed solid).
    pos.push([0.0, 0.0, 0.0]);
    for &(y, r) in &prof {
        for s in 0..SEGMENTS {
            let ph = std::f64::consts::TAU * s as f64 / SEGMENTS as f64;
            // glTF Y-up: the lathe axis is +y; (x, z) is the horizontal plane.
            pos.push([(r * ph.cos()) as f32, y as f32, (-r * ph.sin()) as f32]);
        }
    }
    let top = prof.last().unwrap().0;
    pos.push([0.0, top as f32, 0.0]);
    let ring = |k: usize, s: usize| (1 + k * SEGMENTS + s % SEGMENTS) as u32;
    let last = (pos.len() - 1) as u32;
    let mut idx: Vec<u32> = Vec::new();
    // Counter-clockwise seen from outside (right-handed, Y-up).
    for s in 0..SEGMENTS {
        idx.extend([0, ring(0, s + 1), ring(0, s)]);
    }
    for k in 0..prof.len() - 1 {
        for s in 0..SEGMENTS {
            let (a, b, c, d) = (
                ring(k, s),
                ring(k, s + 1),
                ring(k + 1, s),
                ring(k + 1, s + 1),
            );
            idx.extend([a, b, d, a, d, c]);
        }
    }
    let k = prof.len() - 1;
    for s in 0..SEGMENTS {
        idx.extend([last, ring(k, s), ring(k, s + 1)]);
    }
    let mut bin: Vec<u8> = Vec::new();
    for p in &pos {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for i in &idx {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let idx_len = bin.len() - pos_len;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &pos {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "poser tests/native_amphora.rs"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "amphora", "mesh": 0}],
        "meshes": [{"name": "amphora", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": pos.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": idx_len, "target": 34963}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    let mut js = serde_json::to_vec(&doc).unwrap();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    out
}

fn asset_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/assets/amphora.glb")
}

#[test]
fn committed_amphora_matches_generator() {
    let bytes = amphora_glb();
    let path = asset_path();
    if std::env::var_os("POSER_REGEN_ASSETS").is_some() {
        poser::io::write_atomic(&path, &bytes).unwrap();
    }
    let on_disk = std::fs::read(&path).expect("scenarios/assets/amphora.glb is committed");
    assert!(
        on_disk == bytes,
        "amphora.glb is stale: regenerate with POSER_REGEN_ASSETS=1"
    );
}

#[test]
fn amphora_loads_upright_and_closed() {
    let m = poser::geometry::mesh::load_gltf(&asset_path()).unwrap();
    let (lo, hi) = m.bounds().unwrap();
    // Y-up → Z-up: the lathe axis becomes +z; height 0.58 m, widest radius < 0.2 m.
    // Tolerance 1e-6 m: f32 storage of the vertices.
    assert!(
        (lo.z - 0.0).abs() < 1e-6 && (hi.z - 0.58).abs() < 1e-6,
        "{lo} {hi}"
    );
    assert!(hi.x < 0.2 && lo.x > -0.2 && hi.y < 0.2 && lo.y > -0.2);
    // Closed and outward: the signed volume is positive and every edge is shared by exactly two
    // triangles in opposite directions.
    let vol: f64 = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!(vol > 0.005 && vol < 0.05, "volume {vol}");
    let mut edges = std::collections::BTreeMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1);
        assert_eq!(edges.get(&(b, a)), Some(&1), "open edge {a}-{b}");
    }
}
