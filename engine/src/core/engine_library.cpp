#include "engine_library.h"

#include <msii/core/errors.h>

#include <dlfcn.h>

namespace msii::detail {

const void* loadEngineLibrary(const std::string& name, const char* entry, const std::string& holds)
{
    std::string tried, path = name;
    Dl_info self{};
    if (dladdr(reinterpret_cast<void*>(&loadEngineLibrary), &self) != 0 && self.dli_fname != nullptr) {
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
        throw IOError("cannot load msii's " + holds + " library " + name + " (" + (tried.empty() ? "" : tried + "; ") +
                      (error ? error : "not found") + "): reinstall msii");
    }
    using Entry = const void* (*)();
    const auto call = reinterpret_cast<Entry>(dlsym(handle, entry));
    if (call == nullptr) throw IOError("msii's " + holds + " library " + path + " lacks its entry point: reinstall msii");
    return call();
}

} // namespace msii::detail
