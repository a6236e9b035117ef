//! The k-section speed search (`section_search`) against criteria whose threshold is known
//! in closed form (`reached = value >= threshold`), so the bracket is checked against the
//! true limit, not against the code's earlier output: every `k` brackets the threshold
//! within the tolerance, in `ceil(log(w0 / tol) / log(k + 1))` rounds after the two ends (the
//! k-section law; `k = 1` is bisection, Burden & Faires section 2.1), with `k` probes in
//! flight at once, and the same probes for any thread count. A criterion that is not
//! monotone (two thresholds) is reported as such, with the interval that holds every change
//! of outcome. The real searches over scenes give the same answer for any thread count.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use flexprr_studies::search::{
    Criterion, Probe, Search, SearchConfig, SearchOutcome, section_points, section_search,
};
use flexprr_studies::study::{Study, StudyOptions, run_study};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

fn search(low: f64, high: f64, tolerance: f64) -> Search {
    search_k(low, high, tolerance, 1)
}

fn search_k(low: f64, high: f64, tolerance: f64, k: usize) -> Search {
    Search::from_config(&SearchConfig {
        key: "trajectory.frequency".into(),
        low,
        high,
        tolerance,
        revolutions: None,
        time: Some(0.5),
        criterion: None,
        probes_per_round: Some(k),
    })
    .unwrap()
}

/// A probe of a criterion: `Some(reached)`, or `None` for a failed probe.
fn probe_of(value: f64, reached: Option<bool>) -> Probe {
    Probe {
        value,
        end_s: 0.5,
        reached,
        time_s: None,
        link: None,
        deflection_m: None,
        error: reached.is_none().then(|| "failed on purpose".to_string()),
    }
}

/// Runs `section_search` with `k` probes per round on a pool of `threads` threads.
fn run_on(
    s: &Search,
    k: usize,
    threads: usize,
    criterion: &(dyn Fn(f64) -> Option<bool> + Sync),
) -> SearchOutcome {
    let s = Search {
        probes_per_round: k,
        ..s.clone()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        section_search(
            &s,
            Vec::new(),
            Criterion::Collapse,
            &|v| probe_of(v, criterion(v)),
            &|_, _| {},
        )
    })
}

/// Runs `section_search` with `k` probes per round on a pool of `k` threads.
fn run_k(s: &Search, k: usize, criterion: &(dyn Fn(f64) -> Option<bool> + Sync)) -> SearchOutcome {
    run_on(s, k, k, criterion)
}

/// The rounds the k-section law predicts for a bracket of width `w0`.
fn predicted_rounds(w0: f64, tolerance: f64, k: usize) -> usize {
    ((w0 / tolerance).ln() / ((k + 1) as f64).ln()).ceil() as usize
}

#[test]
fn every_k_brackets_a_known_threshold_in_the_predicted_rounds() {
    let (low, high, tolerance) = (20.0, 34.0, 0.1);
    let s = search(low, high, tolerance);
    // Thresholds: generic, next to either end, and one that is a bisection midpoint.
    for threshold in [24.9173, 20.0001, 33.9999, 27.0, std::f64::consts::PI * 9.0] {
        let mut brackets = Vec::new();
        for k in 1..=6 {
            let o = run_k(&s, k, &|v| Some(v >= threshold));
            let what = format!("threshold {threshold}, k = {k}: {o:?}");
            assert_eq!(o.status, "bracketed", "{what}");
            let (below, above) = (o.below.unwrap(), o.at_or_above.unwrap());
            assert!(below < threshold && threshold <= above, "{what}");
            assert!(above - below <= tolerance, "{what}");
            // The k-section law: 140 = w0/tol is no power of k + 1, so no rounding tie.
            let rounds = predicted_rounds(high - low, tolerance, k);
            assert_eq!(o.rounds, rounds, "{what}");
            assert_eq!(o.probes.len(), 2 + k * rounds, "{what}");
            // The ends first (upper, then lower), then every probe inside the bracket of
            // its round; each probe's answer is the criterion's.
            assert_eq!(
                (o.probes[0].value, o.probes[1].value),
                (high, low),
                "{what}"
            );
            for p in &o.probes {
                assert_eq!(p.reached, Some(p.value >= threshold), "{what}");
            }
            // The bracket is the tightest the probes give: nothing probed inside it.
            assert!(
                o.probes
                    .iter()
                    .all(|p| p.value <= below || p.value >= above),
                "{what}"
            );
            assert!(o.verification.monotone, "{what}");
            assert_eq!(o.verification.transitions.len(), 1, "{what}");
            // The same probes and answer on 1, 2 and 7 threads.
            for threads in [1, 2, 7] {
                let again = run_on(&s, k, threads, &|v| Some(v >= threshold));
                assert_eq!(again, o, "{what}, {threads} threads");
            }
            brackets.push((below, above));
        }
        // Every k brackets the threshold: all brackets overlap.
        let lo = brackets.iter().map(|b| b.0).fold(f64::MIN, f64::max);
        let hi = brackets.iter().map(|b| b.1).fold(f64::MAX, f64::min);
        assert!(lo < hi && hi - lo <= tolerance, "{brackets:?}");
    }
}

#[test]
fn bisection_halves_and_k_section_divides_by_k_plus_one() {
    // k = 1 probes the midpoints; k = 3 the quarter points.
    assert_eq!(section_points(20.0, 34.0, 1), vec![27.0]);
    assert_eq!(section_points(20.0, 36.0, 3), vec![24.0, 28.0, 32.0]);
    // A bracket at the resolution of f64 has no interior point left to probe.
    let x = 1.0e17;
    assert!(section_points(x, x + 16.0, 4).is_empty());
    assert_eq!(section_points(x, x + 64.0, 3).len(), 3);
    let k1 = run_k(&search(20.0, 34.0, 0.1), 1, &|v| Some(v >= 30.3));
    let values: Vec<f64> = k1.probes.iter().map(|p| p.value).collect();
    assert_eq!(&values[..4], &[34.0, 20.0, 27.0, 30.5]);
}

#[test]
fn the_ends_and_failures_decide_as_in_bisection() {
    let s = search(20.0, 34.0, 0.1);
    for k in 1..=4 {
        // Never reached: the upper end says so; bisection does not run the lower end, a
        // round of two runs both and reads the upper first.
        let o = run_k(&s, k, &|_| Some(false));
        assert_eq!(o.status, "high-does-not-reach", "k = {k}");
        assert_eq!((o.below, o.at_or_above), (Some(34.0), None), "k = {k}");
        assert_eq!(o.probes.len(), if k == 1 { 1 } else { 2 }, "k = {k}");
        // Reached everywhere: the lower end says so.
        let o = run_k(&s, k, &|_| Some(true));
        assert_eq!(o.status, "low-reaches", "k = {k}");
        assert_eq!(o.at_or_above, Some(20.0), "k = {k}");
        // The upper end fails: failed, whatever the lower end says.
        let o = run_k(&s, k, &|v| (v < 34.0).then_some(false));
        assert_eq!(o.status, "failed", "k = {k}");
        assert_eq!(o.rounds, 0, "k = {k}");
        // The lower end fails after the upper one reached.
        let o = run_k(&s, k, &|v| (v > 20.0).then_some(true));
        assert_eq!(o.status, "failed", "k = {k}");
        // Every interior probe fails: the first round ends the search, no bracket claimed
        // beyond the ends.
        let o = run_k(&s, k, &|v| match v {
            v if v >= 34.0 => Some(true),
            v if v <= 20.0 => Some(false),
            _ => None,
        });
        assert_eq!(o.status, "failed", "k = {k}");
        assert_eq!(o.rounds, 1, "k = {k}");
        assert_eq!(o.probes.len(), 2 + k, "k = {k}");
        assert_eq!(
            (o.below, o.at_or_above),
            (Some(20.0), Some(34.0)),
            "k = {k}"
        );
        // A failure in the round's part above the limit still ends the search (as a
        // bisection meeting it would).
        let o = run_k(&s, k, &|v| {
            if v > 33.0 && v < 34.0 {
                None
            } else {
                Some(v >= 22.0)
            }
        });
        let hit = o.probes.iter().any(|p| p.reached.is_none());
        assert_eq!(o.status == "failed", hit, "k = {k}: {o:?}");
    }
}

#[test]
fn a_round_keeps_its_k_probes_in_flight_at_once() {
    let (low, high) = (20.0, 34.0);
    let s = search(low, high, 0.1);
    for k in [2, 3, 4] {
        let in_flight = AtomicUsize::new(0);
        let most = AtomicUsize::new(0);
        let threads = Mutex::new(std::collections::HashSet::new());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(k)
            .build()
            .unwrap();
        let s = Search {
            probes_per_round: k,
            ..s.clone()
        };
        let o = pool.install(|| {
            section_search(
                &s,
                Vec::new(),
                Criterion::Collapse,
                &|v| {
                    let expected = if v <= low || v >= high { 2 } else { k };
                    let now = in_flight.fetch_add(1, Ordering::SeqCst) + 1;
                    most.fetch_max(now, Ordering::SeqCst);
                    threads.lock().unwrap().insert(std::thread::current().id());
                    // Wait for the round's other probes to start (a bound only so that a
                    // serial search fails the assertion below instead of hanging).
                    let start = Instant::now();
                    while most.load(Ordering::SeqCst) < expected
                        && start.elapsed() < Duration::from_secs(60)
                    {
                        std::thread::yield_now();
                    }
                    in_flight.fetch_sub(1, Ordering::SeqCst);
                    probe_of(v, Some(v >= 29.0))
                },
                &|_, _| {},
            )
        });
        assert_eq!(o.status, "bracketed");
        assert_eq!(most.load(Ordering::SeqCst), k, "k = {k}");
        assert_eq!(threads.lock().unwrap().len(), k, "k = {k}");
    }
}

/// The KED buckling speed of the paper's machine searched with 1 to 4 threads: the answer
/// moved with the thread count (the thread count chose the probes); the probes are now the
/// study's (`probes_per_round = 3`), so every thread count gives the same probes and the same
/// bracket, within the tolerance, in the rounds the k-section law predicts.
#[test]
fn a_scene_search_gives_the_same_answer_for_any_thread_count() {
    let text = r#"
base = "coupled_f20.toml"
[set.model]
coupling = "ked"
[search]
key = "trajectory.frequency"
low = 20.0
high = 34.0
tolerance = 0.1
time = 0.5
probes_per_round = 3
"#;
    let study = Study::from_text("ked_search.toml", "ked_search", text, &configs()).unwrap();
    let mut brackets = Vec::new();
    let mut rounds = Vec::new();
    let mut probes: Vec<Vec<f64>> = Vec::new();
    for threads in 1..=4 {
        let dir = tempfile::tempdir().unwrap();
        let options = StudyOptions {
            threads: Some(threads),
            ..StudyOptions::default()
        };
        let summary = run_study(&study, dir.path(), &options, &|_, _| {}).unwrap();
        let [o] = &summary.searches[..] else {
            panic!("one search")
        };
        assert_eq!(o.status, "bracketed", "{threads} threads: {o:?}");
        assert_eq!(o.criterion, Criterion::Buckling);
        let (below, above) = (o.below.unwrap(), o.at_or_above.unwrap());
        assert!(
            below < above && above - below <= 0.1,
            "{threads}: {below} {above}"
        );
        // Every probe is on the side of the bracket its answer says.
        for p in &o.probes {
            assert_eq!(p.reached, Some(p.value >= above), "{threads}: {p:?}");
        }
        assert_eq!(o.rounds, predicted_rounds(14.0, 0.1, 3));
        assert!(o.verification.monotone, "{o:?}");
        brackets.push((below, above));
        rounds.push(o.rounds);
        let mut values: Vec<f64> = o.probes.iter().map(|p| p.value).collect();
        values.sort_by(f64::total_cmp);
        probes.push(values);
    }
    assert!(brackets.windows(2).all(|w| w[0] == w[1]), "{brackets:?}");
    assert!(probes.windows(2).all(|w| w[0] == w[1]), "{probes:?}");
    assert_eq!(rounds, vec![4; 4], "{rounds:?}");
}

/// A limit reached on two stretches of the key, [23.5, 26.5] and from 30.7 on: its own probes
/// above the narrowed bracket do not reach it, and the search used to call it "bracketed".
/// It now says "non-monotone", lists the changes of outcome and the contradicting probes,
/// keeps the first onset, and answers with the interval that holds every change seen, the
/// same for every thread count.
#[test]
fn a_non_monotone_outcome_is_reported_with_the_probes_that_show_it() {
    let reached = |v: f64| Some((23.5..=26.5).contains(&v) || v >= 30.7);
    let s = search_k(20.0, 36.0, 0.1, 3);
    let o = run_on(&s, 3, 3, &reached);
    assert_eq!(o.status, "non-monotone", "{o:?}");
    let v = &o.verification;
    assert!(!v.monotone);
    // The first onset is the narrowed bracket around 23.5.
    let (a, b) = v.first_onset.unwrap();
    assert!(a < 23.5 && 23.5 <= b && b - a <= 0.1, "{v:?}");
    // Every change of outcome seen lies in the interval reported, and there are changes
    // both ways: up at 23.5, down after 26.5, up again at 30.7.
    let (below, above) = (o.below.unwrap(), o.at_or_above.unwrap());
    assert!(v.transitions.len() >= 3, "{v:?}");
    for t in &v.transitions {
        assert!(
            below <= t.below && t.above <= above,
            "{t:?} outside ({below}, {above}]"
        );
        // Each change is where the criterion changes.
        assert_ne!(reached(t.below), reached(t.above));
    }
    assert!(v.transitions.iter().any(|t| !t.reached_above));
    // The contradicting probes: not reaching above the first onset.
    assert!(!v.contradicting.is_empty());
    for &x in &v.contradicting {
        assert_eq!(reached(x), Some(false), "{x}");
        assert!(x > b);
    }
    // The same for any thread count.
    for threads in [1, 2, 5] {
        assert_eq!(run_on(&s, 3, threads, &reached), o, "{threads} threads");
    }
    // A monotone criterion is "bracketed" with one change of outcome.
    let o = run_on(&s, 3, 3, &|v| Some(v >= 24.3));
    assert_eq!(o.status, "bracketed");
    assert!(o.verification.monotone && o.verification.contradicting.is_empty());
}

/// A tolerance below the resolution of `f64` near the bracket could never be met: the
/// bracket stops shrinking when its midpoints round onto its ends (bisection then looped
/// for ever). It is refused when the search is read, naming `search.tolerance`.
#[test]
fn a_tolerance_below_the_resolution_of_the_numbers_is_refused() {
    let config = |low: f64, high: f64, tolerance: f64| SearchConfig {
        key: "trajectory.frequency".into(),
        low,
        high,
        tolerance,
        revolutions: None,
        time: Some(0.5),
        criterion: None,
        probes_per_round: None,
    };
    let (key, message) = Search::from_config(&config(1e17, 1e17 + 64.0, 1.0)).unwrap_err();
    assert_eq!(key, "search.tolerance");
    assert!(message.contains("resolution"), "{message}");
    // The same bracket width near 20 is fine, and so is a tolerance just above the bound.
    assert!(Search::from_config(&config(20.0, 84.0, 1.0)).is_ok());
    let s = Search::from_config(&config(1e17, 1e17 + 8192.0, 2048.0)).unwrap();
    let o = run_k(&s, 3, &|v| Some(v >= 1e17 + 3000.0));
    assert_eq!(o.status, "bracketed", "{o:?}");
    assert!(o.at_or_above.unwrap() - o.below.unwrap() <= 2048.0, "{o:?}");
}
