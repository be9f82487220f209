#pragma once
// Private to the engine: the libraries that libmsii loads on first use, so that a run loads
// only the large dependencies it needs. libmsii_levelset holds OpenVDB (the level set, V
// and S on it), libmsii_raster GDAL (rasters in and out, coordinate systems): a mesh run
// does not load GDAL's hundred-odd libraries, a DEM on the height field not OpenVDB's.

#include <string>

namespace msii::detail {

/// The entry point @p entry (an extern "C" function taking nothing and returning a pointer)
/// of the engine library @p name, loaded from the folder of the libmsii that runs this
/// (dladdr: the build tree's and an installation's alike), else by the loader's search path,
/// and called. @p holds: what the library holds, for the error.
/// @throw IOError if the library or its entry point cannot be found.
const void* loadEngineLibrary(const std::string& name, const char* entry, const std::string& holds);

} // namespace msii::detail
