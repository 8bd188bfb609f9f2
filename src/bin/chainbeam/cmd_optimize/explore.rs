//! `chainbeam explore`: a multistart map of the objective's landscape (JSON).

use std::path::Path;

use serde::Serialize;

use chainbeam::multistart::{multistart, MultistartReport};
use chainbeam::optimize::choose_method;

use super::report::{why, LimitsReport};
use super::solve::all_failed;
use super::{DesignReport, ExploreArgs};
use crate::output::{refuse_overwrite, Inputs, Output};
use crate::problem::{self, kind_report, objective_name, AnyProblem, KindReport, Values};
use crate::progress::Progress;
use crate::{check_finite, lib_error, to_json, CliError};

#[derive(Serialize)]
struct StartReport {
    start: usize,
    start_point: Values,
    #[serde(skip_serializing_if = "Option::is_none")]
    objective: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    controls: Option<Values>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gradient_norm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    iterations: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    converged: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    termination: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minimum: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

#[derive(Serialize)]
struct MinimumReport {
    objective: f64,
    controls: Values,
    count: usize,
    best_start: usize,
    starts: Vec<usize>,
}

#[derive(Serialize)]
struct CertificateReport {
    objective: f64,
    controls: Values,
    eigenvalues: Vec<f64>,
    positive_definite: bool,
    free: Vec<usize>,
    asymmetry: f64,
}

#[derive(Serialize)]
struct ExploreReport {
    model: &'static str,
    objective_kind: &'static str,
    effort: f64,
    #[serde(flatten)]
    kind: KindReport,
    control_node: usize,
    method: &'static str,
    #[serde(flatten)]
    limits: LimitsReport,
    design: DesignReport,
    seed: u64,
    starts: usize,
    converged_starts: usize,
    failed_starts: usize,
    seconds: f64,
    /// Parameter indices that do not act on the objective (ignored when clustering).
    inert: Vec<usize>,
    minima: Vec<MinimumReport>,
    results: Vec<StartReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    certificate: Option<CertificateReport>,
}

/// One entry per start, in start order: its start point, its result (or its error) and the
/// minimum it reached; every number checked finite (the error names `results[i]`).
fn start_reports(
    path: &Path,
    report: &MultistartReport,
    problem: &AnyProblem,
) -> Result<Vec<StartReport>, CliError> {
    // Which minimum each start reached.
    let mut minimum_of = vec![None; report.start_points.len()];
    for (m, min) in report.minima.iter().enumerate() {
        for &s in &min.starts {
            if let Some(slot) = minimum_of.get_mut(s) {
                *slot = Some(m);
            }
        }
    }
    let mut results = Vec::with_capacity(report.start_points.len());
    for (start, p) in report.start_points.iter().enumerate() {
        check_finite(path, &format!("results[{start}]"), p)?;
        results.push(StartReport {
            start,
            start_point: problem.layout(p),
            objective: None,
            controls: None,
            gradient_norm: None,
            iterations: None,
            converged: None,
            termination: None,
            minimum: minimum_of[start],
            error: None,
        });
    }
    for (r, &start) in report.results.iter().zip(&report.result_starts) {
        // Never write NaN: check every number.
        let key = format!("results[{start}]");
        check_finite(path, &key, &r.theta)?;
        check_finite(path, &key, &[r.objective, r.gradient_norm])?;
        if let Some(e) = results.get_mut(start) {
            e.objective = Some(r.objective);
            e.controls = Some(problem.layout(&r.theta));
            e.gradient_norm = Some(r.gradient_norm);
            e.iterations = Some(r.iterations);
            e.converged = Some(r.converged);
            e.termination = Some(r.termination.to_string());
        }
    }
    for f in &report.failures {
        if let Some(e) = results.get_mut(f.start) {
            e.error = Some(f.error.to_string());
        }
    }
    Ok(results)
}

/// The distinct minima, every number checked finite (the error names `minima[i]`).
fn minimum_reports(
    path: &Path,
    report: &MultistartReport,
    problem: &AnyProblem,
) -> Result<Vec<MinimumReport>, CliError> {
    let mut minima = Vec::with_capacity(report.minima.len());
    for (i, m) in report.minima.iter().enumerate() {
        let key = format!("minima[{i}]");
        check_finite(path, &key, &[m.objective])?;
        check_finite(path, &key, &m.theta)?;
        minima.push(MinimumReport {
            objective: m.objective,
            controls: problem.layout(&m.theta),
            count: m.count,
            best_start: m.best_start,
            starts: m.starts.clone(),
        });
    }
    Ok(minima)
}

/// The second-order certificate, if the multistart gave one, checked finite.
fn certificate_report(
    path: &Path,
    report: &MultistartReport,
    problem: &AnyProblem,
) -> Result<Option<CertificateReport>, CliError> {
    let Some(c) = &report.certificate else {
        return Ok(None);
    };
    check_finite(path, "certificate.eigenvalues", &c.eigenvalues)?;
    check_finite(path, "certificate", &[c.objective, c.asymmetry])?;
    check_finite(path, "certificate.controls", &c.theta)?;
    Ok(Some(CertificateReport {
        objective: c.objective,
        controls: problem.layout(&c.theta),
        eigenvalues: c.eigenvalues.clone(),
        positive_definite: c.positive_definite,
        free: c.free.clone(),
        asymmetry: c.asymmetry,
    }))
}

/// Runs `explore`.
pub fn run_explore(a: &ExploreArgs, progress: Progress) -> Result<(), CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    let opts = a.solver.options()?;
    problem::check_effort(a.problem.effort)?;
    let mut inputs = Inputs::new();
    let scene = inputs.load_scene(&a.scene)?;
    refuse_overwrite(&[("--output", &out)], &inputs)?;
    let sp = problem::build(&a.scene, &scene, Some(&a.problem), None)?;
    let design = a.design.design(&sp.theta0)?;
    let starts = a.starts as usize;
    let seed = a.parallel.seed;
    let n = sp.theta0.len();
    let spinner = progress.spinner(format!(
        "exploring: {starts} starts of {} on {n} parameter{}",
        choose_method(&sp.problem, &opts).method.name(),
        if n == 1 { "" } else { "s" }
    ));
    let threads = usize::from(a.parallel.threads).min(starts);
    let report = multistart(&sp.problem, &design, starts, seed, threads, &opts);
    spinner.finish_and_clear();
    let report = report.map_err(|e| lib_error(&a.scene, e))?;
    if report.results.is_empty() {
        return Err(all_failed(&a.scene, &report));
    }

    let results = start_reports(&a.scene, &report, &sp.problem)?;
    let minima = minimum_reports(&a.scene, &report, &sp.problem)?;
    let certificate = certificate_report(&a.scene, &report, &sp.problem)?;
    let converged_starts = report.results.iter().filter(|r| r.converged).count();
    let json = ExploreReport {
        model: sp.problem.model_name(),
        objective_kind: objective_name(sp.objective.kind),
        effort: sp.objective.effort,
        kind: kind_report(sp.problem.map()),
        control_node: sp.control_node,
        method: choose_method(&sp.problem, &opts).method.name(),
        limits: LimitsReport::of(&opts),
        design: a.design.describe(),
        seed,
        starts,
        converged_starts,
        failed_starts: report.failures.len(),
        seconds: report.seconds,
        inert: report.inert.clone(),
        minima,
        results,
        certificate,
    };
    out.write_all(&to_json(&json)?)?;
    if converged_starts == starts {
        return Ok(());
    }
    Err(unconverged(&a.scene, &report, starts, converged_starts))
}

/// The exit-status-3 error of a map with starts that did not converge or failed: how many, and
/// the first of each.
fn unconverged(
    path: &Path,
    report: &MultistartReport,
    starts: usize,
    converged_starts: usize,
) -> CliError {
    let first_unconverged = report
        .results
        .iter()
        .zip(&report.result_starts)
        .find(|(r, _)| !r.converged)
        .map(|(r, s)| format!("start {s}: {}", why(r)));
    let first_failed = report
        .failures
        .first()
        .map(|f| format!("start {} failed: {}", f.start, f.error));
    let first = [first_unconverged, first_failed]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join("; ");
    CliError::NotConverged(format!(
        "{}: {} of {starts} starts did not converge ({first}); the map was written, its minima \
         come from the {converged_starts} converged starts",
        path.display(),
        starts - converged_starts,
    ))
}
