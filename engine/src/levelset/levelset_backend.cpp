#include "levelset_backend.h"

#include <msii/core/errors.h>

#ifndef MSII_LEVELSET_BUILTIN
#include <dlfcn.h>
#endif

#include <string>
#include <utility>

namespace msii {
namespace detail {
namespace {

#ifndef MSII_LEVELSET_BUILTIN
/// libmsii_levelset from the folder of the libmsii that runs this (dladdr: the build tree's
/// and an installation's alike), else by the loader's search path.
const LevelSetBackend* loadBackend()
{
    const std::string name = MSII_LEVELSET_LIBRARY;
    std::string tried, path = name;
    Dl_info self{};
    if (dladdr(reinterpret_cast<void*>(&levelSetBackend), &self) != 0 && self.dli_fname != nullptr) {
        const std::string library = self.dli_fname;
        const std::size_t slash = library.rfind('/');
        if (slash != std::string::npos) path = library.substr(0, slash + 1) + name;
    }
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr && path != name) {
        const char* error = dlerror();
        tried = error ? error : path + ": not found";
        handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
    }
    if (handle == nullptr) {
        const char* error = dlerror();
        throw IOError("cannot load msii's level-set library " + name + " (" + (tried.empty() ? "" : tried + "; ") +
                      (error ? error : "not found") + "): reinstall msii");
    }
    using Entry = const LevelSetBackend* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, "msii_levelset_backend"));
    if (entry == nullptr) throw IOError("msii's level-set library " + path + " lacks its entry point: reinstall msii");
    return entry();
}
#endif

} // namespace

const LevelSetBackend& levelSetBackend()
{
#ifdef MSII_LEVELSET_BUILTIN
    return *msii_levelset_backend();
#else
    static const LevelSetBackend* const backend = loadBackend();
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
