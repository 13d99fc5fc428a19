//! Criterion benchmark of the forward-projection solvers per port (poser point by point and
//! batched, vs Refractive COLMAP's Gauss–Newton vs Agrawal's polynomial). Errors:
//! `poser bench projection`.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use poser::bench::projection::{
    agrawal, bench_lens, cases, colmap_gn, poser_project, poser_project_many,
};
use poser::optics::NoSolution;
use poser::optics::port::PortSolver;
use std::hint::black_box;

fn projection(c: &mut Criterion) {
    let lens = bench_lens();
    for case in cases(2000) {
        for (set, pts) in [("ordinary", &case.ordinary), ("grazing", &case.grazing)] {
            let mut g = c.benchmark_group(format!("{}/{}", case.name, set));
            g.throughput(Throughput::Elements(pts.len() as u64));
            let port = case.port;
            g.bench_function("poser", |b| {
                b.iter(|| {
                    for p in pts.iter() {
                        black_box(poser_project(&port, &lens, black_box(*p)).ok());
                    }
                })
            });
            let mut dirs = vec![Err(NoSolution::NoConvergence); pts.len()];
            let mut out = vec![Err(NoSolution::NoConvergence); pts.len()];
            g.bench_function("poser_batch", |b| {
                b.iter(|| {
                    poser_project_many(&port, &lens, black_box(pts), &mut dirs, &mut out);
                    black_box(&out);
                })
            });
            g.sample_size(10);
            g.bench_function("colmap_gn", |b| {
                b.iter(|| {
                    for p in pts.iter() {
                        black_box(colmap_gn(&port, &lens, black_box(*p)).ok());
                    }
                })
            });
            if let PortSolver::Flat(f) = port {
                g.bench_function("agrawal", |b| {
                    b.iter(|| {
                        for p in pts.iter() {
                            black_box(agrawal(&f, &lens, black_box(*p)).ok());
                        }
                    })
                });
            }
            g.finish();
        }
    }
}

criterion_group!(benches, projection);
criterion_main!(benches);
