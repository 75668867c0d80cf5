#pragma once

// Physical and unit constants used across rotorid (SI units everywhere inside the library).

namespace rotorid {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kRadToDeg = 180.0 / kPi;
constexpr double kRpmToRadps = 2.0 * kPi / 60.0;
constexpr double kStandardGravity = 9.80665;  // m/s^2

}  // namespace rotorid
