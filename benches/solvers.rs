//! Assembly, the reference factorization, and every registered solver on the
//! given-friction subproblem and on the whole Coulomb problem, per h.
//! (`contactlab bench` measures the same things quickly up to h = 1/256 and
//! writes results/performance.csv.)

use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solve::{solve_scene, solver_entry};
use contactlab::solvers::numerics::linalg::SparseCholesky;
use contactlab::solvers::{Friction, Silent, registry};
use contactlab::study::bench::pinned;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn scene(k: u32) -> Scene {
    let mut s = Scene::paper_problem(1).unwrap();
    s.set_finest(MeshSize::from_level(k).unwrap());
    s
}

fn bench(c: &mut Criterion) {
    // The binary's allocator policy, so that these agree with `bench`.
    contactlab::allocator::keep_freed_memory();
    faer::set_global_parallelism(faer::Par::Seq);
    let settings = Settings::default();
    let mut group = c.benchmark_group("discretization");
    group.sample_size(10);
    for k in [4u32, 5, 6] {
        let s = scene(k);
        let h = MeshSize::from_level(k).unwrap();
        let label = h.to_string();
        group.bench_with_input(BenchmarkId::new("assembly", &label), &(), |b, _| {
            b.iter(|| black_box(Discretization::new(&s, h).unwrap()))
        });
        let d = Discretization::new(&s, h).unwrap();
        let a = pinned(&d);
        group.bench_with_input(
            BenchmarkId::new("factorization_and_solve", &label),
            &(),
            |b, _| {
                b.iter(|| {
                    let f = SparseCholesky::new(&a).unwrap();
                    let mut x = d.problem.f().to_vec();
                    f.solve_vec(&mut x);
                    black_box(x[0])
                })
            },
        );
    }
    group.finish();
    let mut group = c.benchmark_group("solvers");
    group.sample_size(10);
    for k in [4u32, 5] {
        let s = scene(k);
        let label = MeshSize::from_level(k).unwrap().to_string();
        let g = solve_scene(
            &s,
            Friction::Coulomb,
            solver_entry("newton").unwrap(),
            &settings,
            &mut Silent,
        )
        .unwrap()
        .outcome
        .bound;
        for entry in registry::solvers() {
            group.bench_with_input(
                BenchmarkId::new(format!("given_friction/{}", entry.name), &label),
                &(),
                |b, _| {
                    b.iter(|| {
                        black_box(
                            solve_scene(
                                &s,
                                Friction::Given(&g),
                                solver_entry(entry.name).unwrap(),
                                &settings,
                                &mut Silent,
                            )
                            .map(|x| (x.finest, x.outcome.solution, x.outcome.levels))
                            .unwrap()
                            .1
                            .status,
                        )
                    })
                },
            );
            group.bench_with_input(
                BenchmarkId::new(format!("coulomb/{}", entry.name), &label),
                &(),
                |b, _| {
                    b.iter(|| {
                        black_box(
                            solve_scene(
                                &s,
                                Friction::Coulomb,
                                solver_entry(entry.name).unwrap(),
                                &settings,
                                &mut Silent,
                            )
                            .unwrap()
                            .outcome
                            .claim,
                        )
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
