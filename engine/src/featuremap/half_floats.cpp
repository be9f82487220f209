#include <msii/featuremap/half_floats.h>

#include <Imath/half.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define MSII_HAVE_F16C_PATH 1
#endif

namespace msii {
namespace {

void floatsToHalfPortable(const float* in, std::uint16_t* out, std::size_t n)
{
    for (std::size_t i = 0; i < n; ++i) out[i] = half(in[i]).bits();
}

#ifdef MSII_HAVE_F16C_PATH
__attribute__((target("avx,f16c"))) void floatsToHalfF16c(const float* in, std::uint16_t* out, std::size_t n)
{
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8)
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i),
                         _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
    floatsToHalfPortable(in + i, out + i, n - i);
}
#endif

} // namespace

bool halfConversionUsesF16c()
{
#ifdef MSII_HAVE_F16C_PATH
    static const bool has = __builtin_cpu_supports("avx") && __builtin_cpu_supports("f16c");
    return has;
#else
    return false;
#endif
}

void floatsToHalf(const float* in, std::uint16_t* out, std::size_t n)
{
#ifdef MSII_HAVE_F16C_PATH
    if (halfConversionUsesF16c()) return floatsToHalfF16c(in, out, n);
#endif
    floatsToHalfPortable(in, out, n);
}

} // namespace msii
