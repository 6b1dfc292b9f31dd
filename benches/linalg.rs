//! Criterion benchmarks of the linalg kernels: covariance, eigh, k-means (seeding, Lloyd,
//! predict) and the distance kernel they share. Workloads are smaller than the Python
//! comparison (`benches/bench_linalg.py`) so that `cargo bench` stays short.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use visprim::covariance::covariance;
use visprim::eigh::eigh;
use visprim::kmeans::{kmeans, predict, KMeansParams};
use visprim::kmeanspp::{default_local_trials, kmeans_plusplus, Rng};
use visprim::sqdist::{sq_dists, Panel};

/// Uniform values in [-0.5, 0.5).
fn uniform(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| rng.uniform() - 0.5).collect()
}

/// `n` rows of dimension `d` around 40 random centres (Gaussian-like sums of uniforms).
fn blobs(n: usize, d: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let centres: Vec<f64> = (0..40 * d).map(|_| 20.0 * rng.uniform() - 10.0).collect();
    let mut x = Vec::with_capacity(n * d);
    for _ in 0..n {
        let c = rng.below(40);
        for j in 0..d {
            let noise: f64 = (0..4).map(|_| rng.uniform() - 0.5).sum::<f64>() * 2.0;
            x.push(centres[c * d + j] + noise);
        }
    }
    x
}

fn bench_covariance(c: &mut Criterion) {
    let mut g = c.benchmark_group("covariance");
    g.sample_size(10);
    for &(n, d) in &[(20_000usize, 100usize), (20_000, 400)] {
        let x = uniform(n * d, 1);
        g.throughput(Throughput::Elements((n * d) as u64));
        g.bench_with_input(
            BenchmarkId::from_parameter(format!("{n}x{d}")),
            &x,
            |b, x| b.iter(|| covariance(black_box(x), n, d).unwrap()),
        );
    }
    g.finish();
}

fn bench_eigh(c: &mut Criterion) {
    let mut g = c.benchmark_group("eigh");
    g.sample_size(10);
    for &d in &[100usize, 400] {
        let (_, k) = covariance(&uniform(4 * d * d, 2), 4 * d, d).unwrap();
        g.bench_with_input(BenchmarkId::from_parameter(d), &k, |b, k| {
            b.iter(|| eigh(black_box(k), d, None).unwrap())
        });
    }
    g.finish();
}

fn bench_kmeans(c: &mut Criterion) {
    let (n, d) = (20_000, 30);
    let x = blobs(n, d, 3);
    let mut g = c.benchmark_group("kmeans");
    g.sample_size(10);
    for &k in &[10usize, 100] {
        g.bench_with_input(BenchmarkId::new("seeding", k), &k, |b, &k| {
            b.iter(|| {
                kmeans_plusplus(
                    black_box(&x),
                    n,
                    d,
                    k,
                    default_local_trials(k),
                    &mut Rng::new(0),
                )
            })
        });
        let (init, _) = kmeans_plusplus(&x, n, d, k, default_local_trials(k), &mut Rng::new(0));
        g.bench_with_input(BenchmarkId::new("lloyd_from_init", k), &k, |b, &k| {
            b.iter(|| kmeans(black_box(&x), n, d, &KMeansParams::new(k), Some(&init)).unwrap())
        });
        g.bench_with_input(BenchmarkId::new("full", k), &k, |b, &k| {
            b.iter(|| kmeans(black_box(&x), n, d, &KMeansParams::new(k), None).unwrap())
        });
        g.bench_with_input(BenchmarkId::new("predict", k), &k, |b, &k| {
            b.iter(|| predict(black_box(&x), n, d, &init, k).unwrap())
        });
    }
    g.finish();
}

fn bench_sqdist(c: &mut Criterion) {
    let (n, d, k) = (4096, 30, 176);
    let x = uniform(n * d, 4);
    let centers = uniform(k * d, 5);
    let panel = Panel::from_centers(&centers, k, d);
    let rows: Vec<&[f64]> = x.chunks_exact(d).collect();
    let mut out = vec![0.0; 64 * panel.kpad()];
    let mut g = c.benchmark_group("sqdist");
    g.throughput(Throughput::Elements((n * k * d) as u64));
    g.bench_function("4096x176x30", |b| {
        b.iter(|| {
            for grp in rows.chunks(64) {
                sq_dists(grp, &panel, &mut out);
            }
            black_box(out[0])
        })
    });
    g.finish();
}

criterion_group!(
    group,
    bench_covariance,
    bench_eigh,
    bench_kmeans,
    bench_sqdist
);
criterion_main!(group);
