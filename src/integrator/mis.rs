//! Multiple importance sampling weights (Veach and Guibas 1995).

/// Power heuristic with β = 2 for two strategies, given the density of the
/// strategy that produced the sample (`own`) and of the other one.
pub fn power_heuristic(own: f32, other: f32) -> f32 {
    if own.is_infinite() {
        return 1.0;
    }
    // Divide by the larger density first so the squares cannot overflow.
    let largest = own.max(other);
    if largest.is_nan() || largest <= 0.0 || largest.is_infinite() {
        return if own >= other { 1.0 } else { 0.0 };
    }
    let (a, b) = (own / largest, other / largest);
    a * a / (a * a + b * b)
}

/// The power heuristic (β = 2) applied to one density or density ratio.
pub fn mis(x: f32) -> f32 {
    x * x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_handle_extremes() {
        for (a, b) in [(1.0, 3.0), (0.2, 0.2), (5.0, 0.0), (1e30, 1e30)] {
            assert!((power_heuristic(a, b) + power_heuristic(b, a) - 1.0).abs() < 1e-6);
        }
        assert_eq!(power_heuristic(0.0, 0.0), 1.0);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
    }
}
