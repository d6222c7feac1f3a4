//! Each registered solver's inner kernel (the paper's method: one pointwise
//! relaxation sweep) against one sparse matrix-vector product with the
//! operator it iterates with (problem 1). The kernel is the hot loop; it
//! walks the CSR rows once, like the product.

use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::solvers::numerics::linalg::spmv_into;
use contactlab::solvers::registry;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("kernel_vs_spmv");
    for k in [6u32, 8] {
        let d = Discretization::new(
            &Scene::paper_problem(1).unwrap(),
            MeshSize::from_level(k).unwrap(),
        )
        .unwrap();
        let label = format!("1/{}", 1 << k);
        for entry in registry::solvers() {
            let Some(prepare) = entry.kernel else {
                continue;
            };
            let Some(mut kernel) = prepare(&d.problem) else {
                continue;
            };
            for _ in 0..50 {
                (kernel.step)();
            }
            group.bench_with_input(
                BenchmarkId::new(format!("{}/{}", entry.name, kernel.name), &label),
                &(),
                |b, _| b.iter(|| (kernel.step)()),
            );
            let n = kernel.matrix.nrows();
            let x = vec![1.0; n];
            let mut y = vec![0.0; n];
            group.bench_with_input(
                BenchmarkId::new(format!("{}/spmv", entry.name), &label),
                &(),
                |b, _| {
                    b.iter(|| {
                        spmv_into(&kernel.matrix, black_box(&x), &mut y);
                        black_box(y[0])
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
