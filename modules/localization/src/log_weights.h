// Particle weights in the log domain: log-sum-exp, the effective sample size
// and the adaptive tempering exponent of the scan likelihood.
#pragma once

#include <vector>

namespace carenav::localization {

/** log(exp(a) + exp(b)). */
double logSumExp(double a, double b);

/** log sum_i exp(a_i + b_i) (b empty: log sum_i exp(a_i)), one exp per term. */
double logSumExp(const std::vector<double>& a, const std::vector<double>& b = {});

/** ESS ratio (Kong 1992: ESS = (sum w)^2 / sum w^2, over n) of the weights
 *  exp(a_i + beta l_i). */
double essRatio(const std::vector<double>& a, const std::vector<double>& l, double beta);

/** Tempered (power) likelihood p(z|x)^beta: the largest beta in
 *  [beta_min, 1] whose updated weights keep an ESS ratio of at least
 *  share * ESS(prior), as adaptive tempering in sequential Monte Carlo does
 *  (Jasra, Stephens, Doucet, Tsagaris 2011, "Inference for Levy-driven
 *  stochastic volatility models via adaptive sequential Monte Carlo", sec.
 *  3.2: the next temperature solves ESS(beta) = target; found here by
 *  bisection on log beta). share 0: no tempering (beta 1). */
double temperingExponent(const std::vector<double>& a, const std::vector<double>& l, double share,
                         double beta_min);

}  // namespace carenav::localization
