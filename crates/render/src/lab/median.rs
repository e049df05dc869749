//! The median of timed rounds and per-frame figures: one definition for every measurement.

/// The median of `values`: the middle value of an odd count, the mean of the middle two of
/// an even count (two rounds give their mean, not the slower one); `None` when empty. NaNs
/// sort above every number (`f64::total_cmp`).
///
/// ```
/// use nlrt_render::lab::median;
/// assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
/// assert_eq!(median(vec![4.0, 1.0]), Some(2.5));
/// assert_eq!(median(vec![5.0, 1.0, 4.0, 2.0]), Some(3.0));
/// assert_eq!(median(vec![]), None);
/// ```
#[must_use]
pub fn median(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(values[n / 2]),
        _ => Some(0.5 * (values[n / 2 - 1] + values[n / 2])),
    }
}
