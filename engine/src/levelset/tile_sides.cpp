#include "tile_sides.h"

#include <msii/core/errors.h>

#include <openvdb/tree/LeafManager.h>

#include <array>
#include <memory>
#include <cstdint>
#include <vector>

namespace msii::detail {

void fillTileSides(openvdb::FloatTree& tree, const openvdb::CoordBBox& voxelBox, float outside,
                   float inside, const openvdb::MaskTree* guessed)
{
    using Leaf = openvdb::FloatTree::LeafNodeType;
    using openvdb::Coord;
    constexpr int kLog2 = Leaf::LOG2DIM, kDim = Leaf::DIM;
    const Coord lo(voxelBox.min().x() >> kLog2, voxelBox.min().y() >> kLog2,
                   voxelBox.min().z() >> kLog2);
    const Coord hi(voxelBox.max().x() >> kLog2, voxelBox.max().y() >> kLog2,
                   voxelBox.max().z() >> kLog2);
    const std::int64_t nx = hi.x() - lo.x() + 1, ny = hi.y() - lo.y() + 1, nz = hi.z() - lo.z() + 1;
    if (nx <= 0 || ny <= 0 || nz <= 0) return;
    if (nx * ny * nz > (std::int64_t(1) << 31))
        throw InvalidInputError("the voxel size is too small for a mesh of this extent");
    const auto index = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
        return std::size_t((x * ny + y) * nz + z);
    };

    // State per block: 0 unknown, 1 outside, 2 inside, 3 leaf node.
    enum : std::uint8_t { kUnknown = 0, kOutside = 1, kInside = 2, kLeaf = 3 };
    std::vector<std::uint8_t> state(std::size_t(nx * ny * nz), kUnknown);
    std::vector<const Leaf*> leafs;
    for (auto it = tree.cbeginLeaf(); it; ++it) {
        const Coord b(it->origin().x() >> kLog2, it->origin().y() >> kLog2, it->origin().z() >> kLog2);
        if (b.x() < lo.x() || b.y() < lo.y() || b.z() < lo.z() || b.x() > hi.x() ||
            b.y() > hi.y() || b.z() > hi.z())
            continue;
        state[index(b.x() - lo.x(), b.y() - lo.y(), b.z() - lo.z())] = kLeaf;
        leafs.push_back(it.getLeaf());
    }

    // Seeds: blocks next to a leaf take the side of the leaf's face towards them.
    static constexpr std::array<std::array<int, 3>, 6> kSteps{
        {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};
    std::vector<std::uint32_t> queue;
    std::unique_ptr<openvdb::tree::ValueAccessor<const openvdb::MaskTree>> guessAcc;
    if (guessed) guessAcc = std::make_unique<openvdb::tree::ValueAccessor<const openvdb::MaskTree>>(*guessed);
    for (const Leaf* leaf : leafs) {
        const Coord b(leaf->origin().x() >> kLog2, leaf->origin().y() >> kLog2,
                      leaf->origin().z() >> kLog2);
        for (const auto& s : kSteps) {
            const std::int64_t x = b.x() + s[0] - lo.x(), y = b.y() + s[1] - lo.y(),
                               z = b.z() + s[2] - lo.z();
            if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) continue;
            auto& st = state[index(x, y, z)];
            if (st != kUnknown) continue;
            // Sum of the face voxels' values (a face next to a non-leaf block lies off the
            // surface, so its voxels share one side; the sum outvotes stray ones).
            double sum = 0;
            int count = 0;
            const int axis = s[0] != 0 ? 0 : (s[1] != 0 ? 1 : 2);
            const int layer = (s[0] + s[1] + s[2]) > 0 ? kDim - 1 : 0;
            for (int u = 0; u < kDim; ++u)
                for (int v = 0; v < kDim; ++v) {
                    Coord c = axis == 0 ? Coord(layer, u, v)
                                        : (axis == 1 ? Coord(u, layer, v) : Coord(u, v, layer));
                    const auto offset = Leaf::coordToOffset(c);
                    if (guessAcc && guessAcc->isValueOn(leaf->origin() + c)) continue;
                    sum += leaf->getValue(offset);
                    ++count;
                }
            if (count == 0) continue;
            st = sum < 0 ? kInside : kOutside;
            queue.push_back(std::uint32_t(index(x, y, z)));
        }
    }
    // Breadth first over the remaining blocks.
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::size_t i = queue[head];
        const std::int64_t x = std::int64_t(i) / (ny * nz), y = (std::int64_t(i) / nz) % ny,
                           z = std::int64_t(i) % nz;
        for (const auto& s : kSteps) {
            const std::int64_t xx = x + s[0], yy = y + s[1], zz = z + s[2];
            if (xx < 0 || yy < 0 || zz < 0 || xx >= nx || yy >= ny || zz >= nz) continue;
            auto& st = state[index(xx, yy, zz)];
            if (st != kUnknown) continue;
            st = state[i];
            queue.push_back(std::uint32_t(index(xx, yy, zz)));
        }
    }
    // Write the blocks as leaf-sized tiles.
    for (std::int64_t x = 0; x < nx; ++x)
        for (std::int64_t y = 0; y < ny; ++y)
            for (std::int64_t z = 0; z < nz; ++z) {
                const auto st = state[index(x, y, z)];
                if (st != kOutside && st != kInside) continue;
                const Coord origin((lo.x() + int(x)) << kLog2, (lo.y() + int(y)) << kLog2,
                                   (lo.z() + int(z)) << kLog2);
                tree.addTile(1, origin, st == kInside ? inside : outside, /*active=*/false);
            }
}

void fillLeafSides(openvdb::FloatTree& tree, float magnitude)
{
    using Leaf = openvdb::FloatTree::LeafNodeType;
    constexpr int kDim = Leaf::DIM, kSize = int(Leaf::SIZE);
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    leaves.foreach([magnitude](Leaf& leaf, std::size_t) {
        if (leaf.isValueMaskOn()) return;  // no inactive voxel
        std::array<std::int16_t, kSize> queue;
        std::array<std::uint8_t, kSize> done{};
        int tail = 0;
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            queue[tail++] = std::int16_t(it.pos());
            done[it.pos()] = 1;
        }
        for (int head = 0; head < tail; ++head) {
            const int n = queue[head];
            const int x = n / (kDim * kDim), y = (n / kDim) % kDim, z = n % kDim;
            const bool inside = leaf.getValue(openvdb::Index(n)) < 0;
            const auto visit = [&](int m) {
                if (done[m]) return;
                done[m] = 1;
                leaf.setValueOnly(openvdb::Index(m), inside ? -magnitude : magnitude);
                queue[tail++] = std::int16_t(m);
            };
            if (x > 0) visit(n - kDim * kDim);
            if (x < kDim - 1) visit(n + kDim * kDim);
            if (y > 0) visit(n - kDim);
            if (y < kDim - 1) visit(n + kDim);
            if (z > 0) visit(n - 1);
            if (z < kDim - 1) visit(n + 1);
        }
    });
}

} // namespace msii::detail
