// Reading input files whole, with a size limit and a stop request (docs/limits.md): the scene
// file (LoadScene) and the run-time input table (ReadInputTable). Internal to the io library.
#pragma once

#include <cstddef>
#include <string>

#include "screwfem/solve/stop.h"

namespace screwfem::io_detail {

// The bytes of the file at `path`, read in 64 KiB pieces: at most `limit` bytes, so that a
// file without a size (/dev/zero, a pipe) stops there too, and `stop` polled before every
// piece. `noun` names the file in messages ("scene file"). Throws InputError
//   "PATH: contains a NUL character (not a file name)"
//   "PATH: is a directory, not a NOUN"
//   "PATH: cannot open the NOUN"
//   "PATH: the NOUN is larger than N MiB (the limit)"
//   "PATH: reading the NOUN was interrupted"       (stop requested; the caller tells why)
//   "PATH: cannot read the NOUN"
std::string ReadFileWithLimit(const std::string& path, std::size_t limit, const char* noun,
                              const StopRequest& stop);

}  // namespace screwfem::io_detail
