#pragma once
// Private to the engine: the level set's functions behind msii/levelset/levelset.h and
// msii/invariants/volume_sphere.h. They live in the library that holds OpenVDB
// (libmsii_levelset), which libmsii loads on first use (levelSetBackend); the Python wheel,
// with the engine linked into it, has them built in.
#include <msii/invariants/volume_sphere.h>
#include <msii/levelset/levelset.h>

namespace msii::detail {

struct LevelSetBackend {
    LevelSet (*build)(const TriMesh& mesh, const LevelSetOptions& options, RunContext* context);
    VolumeSphereResult (*volumeSphere)(const TriMesh& mesh, const LevelSet& levelSet,
                                       const VolumeSphereOptions& options, RunContext* context);
    void (*destroy)(LevelSet::Impl* impl);
    const LevelSetInfo& (*info)(const LevelSet::Impl& impl);
    double (*signedDistance)(const LevelSet::Impl& impl, const Vec3& world);
};

/// In the level-set library: buildLevelSet and computeVolumeSphere.
LevelSet buildLevelSetHere(const TriMesh& mesh, const LevelSetOptions& options, RunContext* context);
VolumeSphereResult computeVolumeSphereHere(const TriMesh& mesh, const LevelSet& levelSet,
                                           const VolumeSphereOptions& options, RunContext* context);

/// The level-set library's functions, loaded on the first call.
/// @throw IOError if the library cannot be loaded (named, with where it was looked for).
const LevelSetBackend& levelSetBackend();

} // namespace msii::detail

/// The level-set library's entry point: its functions.
extern "C" const msii::detail::LevelSetBackend* msii_levelset_backend();
