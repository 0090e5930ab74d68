//! Seeded Gaussian noise for `simulate --noise`: splitmix64 for the bits, Box–Muller for
//! the shape. Small, with no dependency, and the same numbers on every platform for a seed.

/// `--noise SIGMA[,seed=N]`: white Gaussian noise of standard deviation `sigma` added to
/// every output, drawn from a generator seeded with `seed`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseSpec {
    /// Standard deviation, in each output's unit (≥ 0).
    pub sigma: f64,
    /// The generator's seed (default 0).
    pub seed: u64,
}

/// Parses `SIGMA` or `SIGMA,seed=N`.
pub fn parse_noise(text: &str) -> Result<NoiseSpec, String> {
    let mut parts = text.split(',');
    let sigma_text = parts.next().unwrap_or_default().trim();
    let sigma: f64 = sigma_text
        .parse()
        .map_err(|_| format!("`{sigma_text}` is not a number (expected SIGMA[,seed=N])"))?;
    if !(sigma.is_finite() && sigma >= 0.0) {
        return Err(format!(
            "the noise's standard deviation must be finite and >= 0, found {sigma_text}"
        ));
    }
    let mut seed = 0;
    for part in parts {
        let part = part.trim();
        let value = part
            .strip_prefix("seed=")
            .ok_or_else(|| format!("unknown noise option `{part}` (expected seed=N)"))?;
        seed = value
            .parse()
            .map_err(|_| format!("`{value}` is not a seed (expected a whole number >= 0)"))?;
    }
    Ok(NoiseSpec { sigma, seed })
}

pub use modelgap::noise::Gaussian;

/// Adds noise of `spec` to every value of every signal, signal after signal, from one
/// generator.
pub fn add_noise(signals: &mut [Vec<f64>], spec: NoiseSpec) {
    if spec.sigma == 0.0 {
        return;
    }
    let mut rng = Gaussian::new(spec.seed);
    for values in signals {
        for v in values {
            *v += spec.sigma * rng.sample();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_numbers_other_seed_other_numbers() {
        let a: Vec<f64> = {
            let mut g = Gaussian::new(1);
            (0..10).map(|_| g.sample()).collect()
        };
        let b: Vec<f64> = {
            let mut g = Gaussian::new(1);
            (0..10).map(|_| g.sample()).collect()
        };
        let c: Vec<f64> = {
            let mut g = Gaussian::new(2);
            (0..10).map(|_| g.sample()).collect()
        };
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn samples_have_zero_mean_and_unit_spread() {
        let mut g = Gaussian::new(7);
        let n = 100_000;
        let x: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        // Standard errors for n = 1e5: 0.0032 on the mean, 0.0045 on the variance;
        // the bounds are about five of them.
        assert!(mean.abs() < 0.016, "{mean}");
        assert!((var - 1.0).abs() < 0.025, "{var}");
    }

    #[test]
    fn noise_spec_parses_sigma_and_seed() {
        assert_eq!(
            parse_noise("1e-4,seed=1"),
            Ok(NoiseSpec {
                sigma: 1e-4,
                seed: 1
            })
        );
        assert_eq!(parse_noise("0.5").map(|s| s.seed), Ok(0));
        assert!(parse_noise("-1").is_err());
        assert!(parse_noise("0.1,seed=x").is_err());
        assert!(parse_noise("0.1,colour=pink").is_err());
    }
}
