#pragma once
/// @file half_floats.h
/// @brief 32-bit floats to 16-bit IEEE halves (the `--half` EXR maps), in bulk.

#include <cstddef>
#include <cstdint>

namespace msii {

/// Converts @p n floats to half bits, rounding to nearest even, exactly as Imath's
/// half(float) (overflow to ±inf, halves below 2^-14 denormal, NaN stays NaN), with the
/// processor's F16C instructions where it has them (8 values per instruction).
void floatsToHalf(const float* in, std::uint16_t* out, std::size_t n);

/// Whether floatsToHalf uses F16C on this processor.
bool halfConversionUsesF16c();

} // namespace msii
