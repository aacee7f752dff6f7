#pragma once
// One template dispatch over effect flags: dispatch_flags(f, b0, b1, ...) calls
// f(std::bool_constant<b0>{}, std::bool_constant<b1>{}, ...) with the run-time flags turned into
// compile-time ones, so each effect set runs a loop body or kernel specialised for it (an effect
// that is off carries no branch and no code). Both engines pick their passes through it; the
// callee reads a flag as `decltype(flag)::value`.
//
//   dispatch_flags([&](auto elastic, auto hourglass) {
//     run<decltype(elastic)::value, decltype(hourglass)::value>();
//   }, effects.elasticity, effects.hourglass);
#include <type_traits>

namespace sinew::simulator {

template <bool... kDone, typename F>
void dispatch_flags(F&& f) {
  f(std::bool_constant<kDone>{}...);
}

template <bool... kDone, typename F, typename... Rest>
void dispatch_flags(F&& f, bool flag, Rest... rest) {
  if (flag)
    dispatch_flags<kDone..., true>(f, rest...);
  else
    dispatch_flags<kDone..., false>(f, rest...);
}

}  // namespace sinew::simulator
