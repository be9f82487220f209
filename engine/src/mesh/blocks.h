#pragma once
// Private to the engine: parallel loops whose partial results are combined in block order,
// so that sums do not depend on the number of threads or on scheduling.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>

namespace msii::detail {

/// Work is split into blocks of this many items whatever the thread count.
constexpr std::size_t kBlock = 1 << 14;

inline std::size_t numBlocks(std::size_t count) { return (count + kBlock - 1) / kBlock; }

/// Runs body(block, begin, end) for every block of [0, count), in parallel.
template <class Body>
void forEachBlock(std::size_t count, const Body& body)
{
    tbb::parallel_for(std::size_t(0), numBlocks(count), [&](std::size_t b) {
        body(b, b * kBlock, std::min(count, (b + 1) * kBlock));
    });
}

} // namespace msii::detail
