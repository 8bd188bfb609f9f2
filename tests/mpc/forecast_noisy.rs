//! The noisy forecast (`[mpc] forecast = "noisy"`, `forecast_error`, `forecast_seed`;
//! src/mpc/forecast.rs): each wave component's complex amplitude A is forecast as
//! A (1 + σ(τ) w) with w a fresh standard complex normal pair per re-plan and
//! σ(τ) = min(e τ / T_p, 1/√2).
//!
//! References: the perfect forecast's closed loop (a noisy forecast with e = 0 adds zeros to
//! the same record, so it must reproduce it bit for bit); the model's own sums (the forecast of
//! a series Re Σ Yⱼ e^{iωⱼ t} differs from the truth by σ(τ) Re Σ Yⱼ wⱼ e^{iωⱼ t}, whose variance
//! over the draws is σ(τ)² Σ|Yⱼ|², computed here from the field's amplitudes, not from the
//! forecast's code).

use chainbeam::model::Chain;
use chainbeam::mpc::{self, forecast_sigma, Forecast, Horizon, Mpc, MpcOptions, NoisyForecast};
use chainbeam::*;

/// riser_300m.toml's pipe and sea at n = 15, h = 0.05 s, held by a drillship-sized vessel whose
/// thrust is the control (tests/mpc/mpc_vessel.rs's `riser_in_waves`), with a surge RAO of
/// 0.1 m/m at 4 s rising to 1 m/m at 30 s (phase −90°), and `extra` added to `[loads.waves]`.
fn riser_in_waves(steps: usize, extra: &str) -> Scene {
    crate::vessel_riser::riser_in_waves_with(
        steps,
        extra,
        "[vessel.rao]\nperiod = [4.0, 30.0]\namplitude = [0.1, 1.0]\nphase = [-90.0, -90.0]\n",
    )
}

fn closed_loop(
    s: &Scene,
    forecast: Forecast,
    error: f64,
    seed: Option<u64>,
) -> mpc::ClosedLoopResult {
    let options = MpcOptions {
        horizon: Horizon::Seconds(4.0),
        effort: 0.0,
        forecast,
        forecast_error: error,
        forecast_seed: seed,
        ..MpcOptions::default()
    };
    let mut c = Mpc::new(s, 1.0, options).unwrap();
    mpc::run_closed_loop(s, 1.0, &mut c).unwrap()
}

/// With e = 0 the noisy forecast adds zeros to the plan's record over its window: the closed
/// loop is the perfect forecast's bit for bit — on a record of every step (linear
/// interpolation) and on a coarser one with derivatives (`record_step`, Hermite), both with
/// the vessel's surge window; the perfect forecast is the default controller bit for bit.
#[test]
fn noisy_with_zero_error_is_the_perfect_forecast_bit_for_bit() {
    for extra in ["", "record_step = 0.2"] {
        let s = riser_in_waves(300, extra);
        let perfect = closed_loop(&s, Forecast::Perfect, 0.1, None);
        let default = {
            let options = MpcOptions {
                horizon: Horizon::Seconds(4.0),
                effort: 0.0,
                ..MpcOptions::default()
            };
            let mut c = Mpc::new(&s, 1.0, options).unwrap();
            mpc::run_closed_loop(&s, 1.0, &mut c).unwrap()
        };
        assert_eq!(perfect.control, default.control, "perfect is the default");
        let zero = closed_loop(&s, Forecast::Noisy, 0.0, None);
        assert_eq!(zero.control, perfect.control, "{extra:?}: e = 0 is perfect");
        assert_eq!(zero.moment, perfect.moment, "{extra:?}");
    }
}

/// A noisy forecast (e = 0.5: σ = 0.26 four seconds ahead at T_p = 7.66 s) decides other
/// thrusts than the perfect one; the same seed reproduces a run bit for bit, another seed gives
/// another run; the default seed is the sea's.
#[test]
fn noisy_differs_from_perfect_and_a_seed_reproduces_it() {
    let s = riser_in_waves(300, "");
    let perfect = closed_loop(&s, Forecast::Perfect, 0.0, None);
    let noisy = closed_loop(&s, Forecast::Noisy, 0.5, Some(7));
    let again = closed_loop(&s, Forecast::Noisy, 0.5, Some(7));
    let other = closed_loop(&s, Forecast::Noisy, 0.5, Some(8));
    let sea_seed = s.loads.waves.as_ref().unwrap().seed;
    let default_seed = closed_loop(&s, Forecast::Noisy, 0.5, None);
    let by_sea_seed = closed_loop(&s, Forecast::Noisy, 0.5, Some(sea_seed));
    let differ = |a: &mpc::ClosedLoopResult, b: &mpc::ClosedLoopResult| {
        a.decisions
            .iter()
            .zip(&b.decisions)
            .any(|(x, y)| x.control != y.control)
    };
    println!(
        "c_sum perfect {} noisy(7) {} noisy(8) {}",
        perfect.summary.c_sum, noisy.summary.c_sum, other.summary.c_sum
    );
    assert!(
        differ(&perfect, &noisy),
        "a noisy plan decides other thrusts"
    );
    assert_eq!(noisy.control, again.control, "the same seed, the same run");
    assert_eq!(noisy.moment, again.moment);
    assert!(differ(&noisy, &other), "another seed, another forecast");
    assert_eq!(
        default_seed.control, by_sea_seed.control,
        "default: the sea's seed"
    );
}

/// The spread of the forecast's error grows with lead time as documented: over K draws, the
/// error of the water momentum Wᵢ of a pendulum near the surface and of the vessel's surge X_w
/// at lead τ has the standard deviation σ(τ) √(Σⱼ |Yⱼ|²) (Yⱼ the series' amplitudes, read from
/// the true field), and is exactly 0 at τ ≤ 0 (the decision's present and the plan's start
/// one step back). The sea has 300 components (so that K = 2000 draws are cheap); the sample
/// variance of K independent normal values has a relative standard error √(2/K) = 3.2 %, so
/// the standard deviation's ≈ 1.6 %: the tolerance is 4 of those, 6.3 %. On the record of
/// every step the error between the knots (every ⌊T_p/(40 h)⌋ = 3 steps) is interpolated
/// linearly: 0.3 % at most at the peak period, well inside the tolerance.
#[test]
fn the_error_spread_grows_with_lead_time_as_documented() {
    let (k_draws, error) = (2000usize, 0.3);
    for extra in ["components = 300", "components = 300\nrecord_step = 0.2"] {
        let s = riser_in_waves(400, extra);
        let tp = s.loads.waves.as_ref().unwrap().tp;
        let record = Chain::<f64, 2>::from_scene(&s).unwrap();
        let field = record.waves().unwrap();
        let vessel = record.vessel().unwrap();
        let i = 13;
        let var =
            |y: &[chainbeam::ocean::Complex<f64>]| y.iter().map(|c| c.norm_sqr()).sum::<f64>();
        let (w_var, x_var) = (
            var(field.amplitudes(i, false)),
            var(vessel.surge_amplitudes().unwrap()),
        );
        let mut noisy = NoisyForecast::new(&s, error, Some(3)).unwrap();
        let t0 = 6.0;
        // Leads on the grid of both records: 0.6 s (3 steps), 2.4, 6.0, 12.0 s; and the start.
        let leads = [-0.05, 0.0, 0.6, 2.4, 6.0, 12.0];
        let mut sums = vec![[0.0f64; 2]; leads.len()];
        for _ in 0..k_draws {
            let f = noisy
                .forecast_chain(&record, t0, (t0 - 0.05, t0 + 12.0))
                .unwrap();
            let (fw, fv) = (f.waves().unwrap(), f.vessel().unwrap());
            for (l, &tau) in leads.iter().enumerate() {
                let t = t0 + tau;
                let dw = fw.momentum(i, t) - field.momentum(i, t);
                let dx = fv.at(t)[0] - vessel.at(t)[0];
                if tau <= 0.0 {
                    assert_eq!(dw, 0.0, "{extra}: no error at τ = {tau}");
                    assert_eq!(dx, 0.0, "{extra}: no error at τ = {tau}");
                }
                sums[l][0] += dw * dw;
                sums[l][1] += dx * dx;
            }
        }
        for (l, &tau) in leads.iter().enumerate().filter(|(_, &t)| t > 0.0) {
            let sigma = forecast_sigma(error, tp, tau);
            let expect = [sigma * w_var.sqrt(), sigma * x_var.sqrt()];
            for (c, name) in ["W_13", "X_w"].iter().enumerate() {
                let got = (sums[l][c] / k_draws as f64).sqrt();
                println!(
                    "{extra:?} τ = {tau:5.2} s: σ = {sigma:.4}, std of {name} error {got:.6e}, \
                     expected {:.6e} ({:+.2} %)",
                    expect[c],
                    100.0 * (got / expect[c] - 1.0)
                );
                assert!(
                    (got / expect[c] - 1.0).abs() < 0.063,
                    "{extra}: τ = {tau}: {name} std {got} against {}",
                    expect[c]
                );
            }
        }
    }
}

/// σ(τ) as documented: 0 up to the present, e τ / T_p, capped at 1/√2.
#[test]
fn sigma_grows_linearly_then_caps() {
    assert_eq!(forecast_sigma(0.1, 8.0, -1.0), 0.0);
    assert_eq!(forecast_sigma(0.1, 8.0, 0.0), 0.0);
    assert!((forecast_sigma(0.1, 8.0, 8.0) - 0.1).abs() < 1e-15);
    assert!((forecast_sigma(0.1, 8.0, 16.0) - 0.2).abs() < 1e-15);
    assert_eq!(forecast_sigma(0.1, 8.0, 1e3), mpc::SIGMA_CAP);
    assert_eq!(mpc::SIGMA_CAP, 0.5f64.sqrt());
}

/// Bad values are refused naming the key: the scene's `mpc.forecast_error` (negative, NaN,
/// beyond 100) and `mpc.forecast_seed` (negative), an unknown forecast naming `mpc.forecast`;
/// "noisy" on a scene without a sea names `forecast`; the library refuses a negative error by
/// its argument.
#[test]
fn bad_forecast_values_are_refused_by_name() {
    let base = riser_in_waves(40, "");
    let text = base.to_toml_string();
    for (extra, key) in [
        ("forecast_error = -0.1", "mpc.forecast_error"),
        ("forecast_error = nan", "mpc.forecast_error"),
        ("forecast_error = 101.0", "mpc.forecast_error"),
        ("forecast_seed = -1", "mpc.forecast_seed"),
        ("forecast = \"fuzzy\"", "mpc.forecast"),
    ] {
        let e = Scene::from_toml_str(&format!("{text}\n[mpc]\n{extra}\n")).unwrap_err();
        assert!(e.to_string().contains(key), "{extra}: {e}");
    }
    let ok = Scene::from_toml_str(&format!(
        "{text}\n[mpc]\nforecast = \"noisy\"\nforecast_error = 0.25\nforecast_seed = 9\n"
    ))
    .unwrap();
    let t = ok.mpc.unwrap();
    assert_eq!(t.forecast, Some(Forecast::Noisy));
    assert_eq!(t.forecast_error, Some(0.25));
    assert_eq!(t.forecast_seed, Some(9));
    let mut calm = base.clone();
    calm.loads.waves = None;
    let e = Mpc::new(
        &calm,
        1.0,
        MpcOptions {
            forecast: Forecast::Noisy,
            ..MpcOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::Mpc(mpc::MpcError::ForecastWithoutSea)),
        "{e:?}"
    );
    let e = Mpc::new(
        &base,
        1.0,
        MpcOptions {
            forecast: Forecast::Noisy,
            forecast_error: -1.0,
            ..MpcOptions::default()
        },
    )
    .unwrap_err();
    match e {
        Error::Mpc(m @ mpc::MpcError::ForecastError { .. }) => {
            assert_eq!(m.argument(), "forecast_error")
        }
        other => panic!("{other:?}"),
    }
}
