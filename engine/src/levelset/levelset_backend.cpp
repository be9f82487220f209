#include "levelset_backend.h"

#include <msii/core/errors.h>

#ifndef MSII_LEVELSET_BUILTIN
#include "../core/engine_library.h"
#endif

#include <string>
#include <utility>

namespace msii {
namespace detail {

const LevelSetBackend& levelSetBackend()
{
#ifdef MSII_LEVELSET_BUILTIN
    return *msii_levelset_backend();
#else
    static const LevelSetBackend* const backend = static_cast<const LevelSetBackend*>(
        loadEngineLibrary(MSII_LEVELSET_LIBRARY, "msii_levelset_backend", "level-set"));
    return *backend;
#endif
}

} // namespace detail

void LevelSet::ImplDeleter::operator()(Impl* impl) const
{
    if (impl != nullptr) detail::levelSetBackend().destroy(impl);
}

LevelSet::LevelSet(std::unique_ptr<Impl, ImplDeleter> impl) : mImpl(std::move(impl)) {}
LevelSet::~LevelSet() = default;
LevelSet::LevelSet(LevelSet&&) noexcept = default;
LevelSet& LevelSet::operator=(LevelSet&&) noexcept = default;

const LevelSetInfo& LevelSet::info() const { return detail::levelSetBackend().info(*mImpl); }

double LevelSet::signedDistance(const Vec3& world) const
{
    return detail::levelSetBackend().signedDistance(*mImpl, world);
}

const LevelSet::Impl& levelSetImpl(const LevelSet& levelSet) { return *levelSet.mImpl; }

LevelSet buildLevelSet(const TriMesh& mesh, const LevelSetOptions& options, RunContext* context)
{
    return detail::levelSetBackend().build(mesh, options, context);
}

VolumeSphereResult computeVolumeSphere(const TriMesh& mesh, const LevelSet& levelSet, const VolumeSphereOptions& options,
                                       RunContext* context)
{
    return detail::levelSetBackend().volumeSphere(mesh, levelSet, options, context);
}

} // namespace msii
