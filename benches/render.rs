//! Criterion benchmarks of the native renderer: one small image of the benchmark scene
//! (strobe backscatter through a flat port), BVH build of a procedural reef, and ray casts.
//! The speed-against-error comparison with Mitsuba and Cycles is `poser bench render`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use poser::backend::native::{render_image, scene};
use poser::bench::render::bench_model;
use poser::geometry::{Bvh, Ray, SurfaceId, mesh};
use std::hint::black_box;

fn image(c: &mut Criterion) {
    let model = bench_model(80, 60);
    let sc = scene::Scene::build(&model).unwrap();
    let mut g = c.benchmark_group("render");
    g.sample_size(10);
    g.bench_function("strobe_backscatter_80x60_4spp", |b| {
        b.iter(|| render_image(black_box(&model), &sc, 0, 0, 4, None).unwrap())
    });
    g.finish();
}

fn reef() -> Vec<(SurfaceId, mesh::TriMesh)> {
    vec![
        (
            SurfaceId::Object(0),
            mesh::seabed(16.0, 12.0, 0.15, 0.05, 7, None).unwrap(),
        ),
        (
            SurfaceId::Object(1),
            mesh::boulders(12.0, 8.0, 25, 0.35, 11),
        ),
    ]
}

fn bvh(c: &mut Criterion) {
    let meshes = reef();
    let mut g = c.benchmark_group("bvh");
    g.sample_size(10);
    g.bench_function("build_reef_185k_tris", |b| {
        b.iter(|| Bvh::from_meshes(black_box(meshes.clone())))
    });
    let sc = Bvh::from_meshes(meshes);
    g.bench_function("intersect_10k_rays", |b| {
        b.iter(|| {
            let mut n = 0;
            for k in 0..10_000u64 {
                let x = (k % 100) as f64 * 0.08 - 4.0;
                let y = (k / 100) as f64 * 0.05 - 2.5;
                let d = DVec3::new(0.1 * (x * 3.1).sin(), 0.1 * (y * 2.7).cos(), -1.0).normalize();
                let r = Ray {
                    origin: DVec3::new(x, y, 2.0),
                    dir: d,
                };
                n += sc.intersect(&r, f64::INFINITY).is_some() as u32;
            }
            n
        })
    });
    g.finish();
}

criterion_group!(benches, image, bvh);
criterion_main!(benches);
