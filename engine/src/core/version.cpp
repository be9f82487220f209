#include <msii/core/version.h>
#include <msii/core/version_config.h>

namespace msii {

const char* versionString() { return MSII_VERSION_STRING; }

} // namespace msii
