//! One pointwise relaxation sweep against one sparse matrix-vector product of
//! the same matrix H = A + M (problem 1). The sweep is the hot loop of the
//! paper's method; it walks the CSR rows once, like the product.

use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::solvers::RelaxationSettings;
use contactlab::solvers::linalg::spmv_into;
use contactlab::study::bench::SweepFixture;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("sweep_vs_spmv");
    for k in [6u32, 8] {
        let d = Discretization::new(
            &Scene::paper_problem(1).unwrap(),
            MeshSize::from_level(k).unwrap(),
        )
        .unwrap();
        let p = &d.problem;
        let n = p.n();
        let settings = RelaxationSettings::default();
        let fixture = SweepFixture::new(p, &settings);
        let (op, data) = (&fixture.op, fixture.data(p));
        let mut v = vec![0.0; n];
        for _ in 0..50 {
            op.sweep(&mut v, &data);
        }
        let label = format!("1/{}", 1 << k);
        group.bench_with_input(BenchmarkId::new("sweep", &label), &(), |b, _| {
            b.iter(|| black_box(op.sweep(black_box(&mut v), &data)))
        });
        let x = v.clone();
        let mut y = vec![0.0; n];
        group.bench_with_input(BenchmarkId::new("spmv", &label), &(), |b, _| {
            b.iter(|| {
                spmv_into(&op.h, black_box(&x), &mut y);
                black_box(y[0])
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
