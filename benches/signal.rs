//! Criterion benchmarks of the signal kernels on the workload: 10,000 trials x 4
//! channels x 150 frames (filtering, zero-velocity crossings, resampling), plus one lockstep
//! block per instruction-set level and width (single thread).
//!
//! `cargo bench --bench signal` (all), `cargo bench --bench signal -- block` (one group).

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use visprim::filter::{butter_sos, sections, sosfiltfilt_ragged, sosfiltfilt_rows};
use visprim::lanes::run_block;
use visprim::resample::resample_segments;
use visprim::zvc::zero_velocity_crossings_ragged;

const TRIALS: usize = 10_000;
const CHANNELS: usize = 4;
const FRAMES: usize = 150;

/// Deterministic uniform numbers in [0, 1) (splitmix64), so the bench needs no rand crate.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Smooth arm-like angles: per trial and channel a sum of three slow sinusoids plus a little
/// noise, `(TRIALS * FRAMES, CHANNELS)` row-major, and the trial offsets.
fn corpus() -> (Vec<f64>, Vec<i64>) {
    let mut rng = Rng(7);
    let mut v = vec![0.0; TRIALS * FRAMES * CHANNELS];
    for tr in 0..TRIALS {
        for c in 0..CHANNELS {
            let comps: Vec<(f64, f64, f64)> = (0..3)
                .map(|_| {
                    (
                        rng.next(),
                        0.3 + 1.5 * rng.next(),
                        std::f64::consts::TAU * rng.next(),
                    )
                })
                .collect();
            for t in 0..FRAMES {
                let s = t as f64 / FRAMES as f64;
                let x: f64 = comps
                    .iter()
                    .map(|&(a, f, p)| a * (std::f64::consts::TAU * f * s + p).sin())
                    .sum();
                v[(tr * FRAMES + t) * CHANNELS + c] = x + 0.01 * (rng.next() - 0.5);
            }
        }
    }
    let offsets = (0..TRIALS as i64).map(|i| i * FRAMES as i64).collect();
    (v, offsets)
}

fn velocity(values: &[f64]) -> Vec<f64> {
    // Per-trial forward difference (the last frame repeats the previous difference).
    let mut vel = vec![0.0; values.len()];
    for tr in 0..TRIALS {
        for t in 0..FRAMES {
            let t1 = if t + 1 < FRAMES { t + 1 } else { t };
            let t0 = t1 - 1;
            for c in 0..CHANNELS {
                let i = |t: usize| (tr * FRAMES + t) * CHANNELS + c;
                vel[i(t)] = values[i(t1)] - values[i(t0)];
            }
        }
    }
    vel
}

fn bench_filter(c: &mut Criterion) {
    c.bench_function("butter_sos/order10", |b| {
        b.iter(|| butter_sos(black_box(10), black_box(0.25)).unwrap())
    });
    let sos = butter_sos(10, 0.25).unwrap();
    let (values, offsets) = corpus();
    let mut g = c.benchmark_group("sosfiltfilt_ragged");
    g.sample_size(20).measurement_time(Duration::from_secs(8));
    g.throughput(Throughput::Elements(values.len() as u64));
    g.bench_function("10000x4x150/order10", |b| {
        b.iter(|| sosfiltfilt_ragged(&sos, black_box(&values), CHANNELS, &offsets, None).unwrap())
    });
    g.finish();
    // The same signals as rows (signals, frames): `sosfiltfilt` of a 2-D array.
    let mut rows = vec![0.0; values.len()];
    for tr in 0..TRIALS {
        for t in 0..FRAMES {
            for c in 0..CHANNELS {
                rows[(tr * CHANNELS + c) * FRAMES + t] = values[(tr * FRAMES + t) * CHANNELS + c];
            }
        }
    }
    let mut g = c.benchmark_group("sosfiltfilt_rows");
    g.sample_size(20).measurement_time(Duration::from_secs(8));
    g.throughput(Throughput::Elements(rows.len() as u64));
    g.bench_function("40000x150/order10", |b| {
        b.iter(|| {
            sosfiltfilt_rows(&sos, black_box(&rows), TRIALS * CHANNELS, FRAMES, None).unwrap()
        })
    });
    g.finish();
}

fn block_bench<const W: usize>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
) {
    let secs = sections(&butter_sos(10, 0.25).unwrap());
    let len = FRAMES + 2 * 33;
    let mut rng = Rng(11);
    let template: Vec<[f64; W]> = (0..len)
        .map(|_| std::array::from_fn(|_| rng.next() - 0.5))
        .collect();
    let mut buf = template.clone();
    for level in visprim::simd::levels() {
        g.throughput(Throughput::Elements((W * FRAMES) as u64));
        g.bench_function(format!("{level:?}/w{W}/fused"), |b| {
            b.iter(|| {
                buf.copy_from_slice(&template);
                run_block::<W, true>(level, &secs, black_box(&mut buf));
            })
        });
        g.bench_function(format!("{level:?}/w{W}/single"), |b| {
            b.iter(|| {
                buf.copy_from_slice(&template);
                run_block::<W, false>(level, &secs, black_box(&mut buf));
            })
        });
    }
}

fn bench_block(c: &mut Criterion) {
    let mut g = c.benchmark_group("block");
    g.sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(1));
    block_bench::<8>(&mut g);
    block_bench::<16>(&mut g);
    block_bench::<32>(&mut g);
    block_bench::<64>(&mut g);
    g.finish();
}

fn bench_zvc_resample(c: &mut Criterion) {
    // As in the pipeline: filtered angles, their velocity, crossings, segments.
    let (raw, offsets) = corpus();
    let sos = butter_sos(10, 0.25).unwrap();
    let values = sosfiltfilt_ragged(&sos, &raw, CHANNELS, &offsets, None).unwrap();
    let vel = velocity(&values);
    let mut g = c.benchmark_group("zvc_resample");
    g.sample_size(20).measurement_time(Duration::from_secs(5));
    g.throughput(Throughput::Elements(vel.len() as u64));
    g.bench_function("zvc_ragged/10000x4x150", |b| {
        b.iter(|| {
            zero_velocity_crossings_ragged(black_box(&vel), CHANNELS, &offsets, 0.05, Some(&values))
                .unwrap()
        })
    });
    // Segments between consecutive kept crossings of channel 0 of each trial (global frames).
    let cr = zero_velocity_crossings_ragged(&vel, CHANNELS, &offsets, 0.05, Some(&values)).unwrap();
    let (mut starts, mut ends) = (Vec::new(), Vec::new());
    for i in 1..cr.frame.len() {
        if cr.trial[i] == cr.trial[i - 1] && cr.channel[i] == 0 && cr.channel[i - 1] == 0 {
            let base = offsets[cr.trial[i] as usize] as f64;
            starts.push(base + cr.frame[i - 1]);
            ends.push(base + cr.frame[i]);
        }
    }
    g.throughput(Throughput::Elements((starts.len() * CHANNELS * 100) as u64));
    g.bench_function(format!("resample_segments/{}x4x100", starts.len()), |b| {
        b.iter(|| resample_segments(black_box(&values), CHANNELS, &starts, &ends, 100).unwrap())
    });
    g.finish();
}

criterion_group!(group, bench_filter, bench_block, bench_zvc_resample);
criterion_main!(group);
