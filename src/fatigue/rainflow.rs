//! Rainflow counting per ASTM E1049-85 (reapproved 2011), §5.4.4 "Rainflow Counting", in one
//! streaming pass: O(N) time, and no allocation once the workspace has grown to the deepest
//! stack of unpaired turning points (at most the number of turning points; for a stationary
//! record a few dozen).
//!
//! 1. **Turning points.** The first and the last sample, and every sample where the slope
//!    changes sign. A plateau (equal consecutive samples) is one turning point, at its last
//!    sample, so a cycle's indices point into the series (the convention of the `rainflow`
//!    Python package, whose cycles the tests reproduce).
//! 2. **Three-point rule.** With the three most recent points on the stack, X = |latest range|,
//!    Y = |previous range|. If X < Y, read the next point. Otherwise, if Y contains the starting
//!    point S (the stack holds exactly three points), count Y as a half cycle and discard its
//!    first point (S moves to Y's second point); else count Y as one cycle and discard its two
//!    points. Repeat.
//! 3. **Residue.** At the end of the record every range left on the stack is a half cycle.
//!
//! The standard's worked example (Fig. 6, Table 4: −2, 1, −3, 5, −1, 3, −4, 4, −2) gives half
//! cycles of ranges 3, 6, 9 and 4, and full cycles of 4 and 8 (tests/fatigue/fatigue.rs).

use super::FatigueError;

/// One counted cycle: the range, the mean, the count and the indices of its two turning points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cycle {
    /// Δσ = |x_end − x_start|.
    pub range: f64,
    /// (x_start + x_end)/2.
    pub mean: f64,
    /// 1 for a full cycle, 0.5 for a half cycle (ASTM E1049-85 §5.4.4, steps 5 and 6).
    pub count: f64,
    /// Index in the series of the cycle's first turning point.
    pub start: usize,
    /// Index in the series of the cycle's second turning point (`start < end`).
    pub end: usize,
}

/// The reusable stack of unpaired turning points (index, value). Keep one per thread and pass
/// it to every count: after the first call it holds its capacity, and a count over a series no
/// rougher than the ones before allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct RainflowWorkspace {
    stack: Vec<(usize, f64)>,
}

impl RainflowWorkspace {
    /// An empty workspace (it grows on first use).
    pub fn new() -> Self {
        Self::default()
    }

    /// A workspace that never allocates for a stack of up to `capacity` unpaired turning points
    /// (`capacity` = the series' length is always enough).
    pub fn with_capacity(capacity: usize) -> Self {
        RainflowWorkspace {
            stack: Vec::with_capacity(capacity),
        }
    }

    /// The number of turning points the workspace holds without allocating.
    pub fn capacity(&self) -> usize {
        self.stack.capacity()
    }
}

fn cycle(a: (usize, f64), b: (usize, f64), count: f64) -> Cycle {
    Cycle {
        range: (b.1 - a.1).abs(),
        mean: 0.5 * (a.1 + b.1),
        count,
        start: a.0,
        end: b.0,
    }
}

/// Applies the three-point rule (step 2 of the module's docs) after a new turning point was
/// pushed.
fn pair<F: FnMut(Cycle)>(stack: &mut Vec<(usize, f64)>, visit: &mut F) {
    while stack.len() >= 3 {
        let n = stack.len();
        let (p1, p2, p3) = (stack[n - 3], stack[n - 2], stack[n - 1]);
        let x = (p3.1 - p2.1).abs();
        let y = (p2.1 - p1.1).abs();
        if x < y {
            return;
        }
        if n == 3 {
            // Y contains the starting point: a half cycle; S moves to Y's second point.
            visit(cycle(p1, p2, 0.5));
            stack.remove(0);
        } else {
            visit(cycle(p1, p2, 1.0));
            stack.truncate(n - 3);
            stack.push(p3);
        }
    }
}

/// Streams the turning points of `series` (step 1 of the module's docs) into `sink`.
// A plateau is exactly equal consecutive samples (as in the standard and the `rainflow`
// package): any tolerance would merge distinct turning points.
#[allow(clippy::float_cmp)]
fn turning_points<I, F>(series: I, mut sink: F) -> Result<(), FatigueError>
where
    I: IntoIterator<Item = f64>,
    F: FnMut((usize, f64)),
{
    // `x` is the candidate turning point: the latest sample that differs from the one before;
    // `x_index` the last index of its plateau; `slope` the sign of the step into it.
    let mut x: Option<(usize, f64)> = None;
    let mut slope = 0.0_f64;
    for (i, v) in series.into_iter().enumerate() {
        if !v.is_finite() {
            return Err(FatigueError::NonFinite {
                quantity: "stress",
                index: i,
                value: v,
            });
        }
        match x {
            None => {
                sink((i, v));
                x = Some((i, v));
            }
            Some((_, xv)) if v == xv => x = Some((i, xv)),
            Some((xi, xv)) => {
                let step = v - xv;
                if (slope > 0.0 && step < 0.0) || (slope < 0.0 && step > 0.0) {
                    sink((xi, xv));
                }
                slope = step;
                x = Some((i, v));
            }
        }
    }
    // The last sample closes the record (unless the record is one plateau).
    if let Some((xi, xv)) = x {
        if slope != 0.0 {
            sink((xi, xv));
        }
    }
    Ok(())
}

/// Counts the cycles of a series per ASTM E1049-85 §5.4.4 (the module's docs) and hands each
/// to `visit` in the order the standard counts them; the residue's half cycles come last, in
/// the order of the record. Allocation-free once `workspace` is large enough; O(N).
///
/// # Errors
/// [`FatigueError::NonFinite`] at the first NaN or infinite sample (nothing after it is
/// counted; cycles counted before it have been visited).
pub fn rainflow_visit<I, F>(
    series: I,
    workspace: &mut RainflowWorkspace,
    mut visit: F,
) -> Result<(), FatigueError>
where
    I: IntoIterator<Item = f64>,
    F: FnMut(Cycle),
{
    let stack = &mut workspace.stack;
    stack.clear();
    turning_points(series, |p| {
        stack.push(p);
        pair(stack, &mut visit);
    })?;
    for w in stack.windows(2) {
        visit(cycle(w[0], w[1], 0.5));
    }
    stack.clear();
    Ok(())
}

/// Appends the cycles of `series` to `cycles` (see [`rainflow_visit`]); `cycles` is cleared
/// first and keeps its capacity between calls.
///
/// # Errors
/// [`FatigueError::NonFinite`] at the first NaN or infinite sample.
pub fn rainflow_into(
    series: &[f64],
    workspace: &mut RainflowWorkspace,
    cycles: &mut Vec<Cycle>,
) -> Result<(), FatigueError> {
    cycles.clear();
    rainflow_visit(series.iter().copied(), workspace, |c| cycles.push(c))
}

/// The cycles of `series` per ASTM E1049-85 §5.4.4 (allocating convenience over
/// [`rainflow_visit`]).
///
/// ```
/// use chainbeam::fatigue::rainflow;
/// // ASTM E1049-85 Fig. 6 / Table 4.
/// let cycles = rainflow(&[-2.0, 1.0, -3.0, 5.0, -1.0, 3.0, -4.0, 4.0, -2.0])?;
/// let full: f64 = cycles.iter().filter(|c| c.range == 8.0).map(|c| c.count).sum();
/// assert_eq!(full, 1.0);
/// # Ok::<(), chainbeam::fatigue::FatigueError>(())
/// ```
///
/// # Errors
/// [`FatigueError::NonFinite`] at the first NaN or infinite sample.
pub fn rainflow(series: &[f64]) -> Result<Vec<Cycle>, FatigueError> {
    let mut cycles = Vec::new();
    rainflow_into(series, &mut RainflowWorkspace::new(), &mut cycles)?;
    Ok(cycles)
}
