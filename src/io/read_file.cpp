#include "read_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "screwfem/model/errors.h"

namespace screwfem::io_detail {

namespace {

// Closes the descriptor on every way out.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) close(fd);
  }
};

}  // namespace

// POSIX open and read rather than a stream: a signal interrupts a blocked read (a pipe or a
// FIFO without a writer) with EINTR, where the stream library would retry; the stop request is
// then polled, as it is before every piece.
std::string ReadFileWithLimit(const std::string& path, std::size_t limit, const char* noun,
                              const StopRequest& stop) {
  const std::string the_noun = std::string("the ") + noun;
  if (path.find('\0') != std::string::npos)
    throw InputError(std::string(noun) + " path '" + std::string(path.c_str()) +
                     "...': contains a NUL character (not a file name)");
  const auto interrupted = [&] {
    return InputError(path + ": reading " + the_noun + " was interrupted");
  };
  struct stat info {};
  if (stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode))
    throw InputError(path + ": is a directory, not " +
                     (std::strchr("aeiou", noun[0]) != nullptr ? "an " : "a ") + noun);
  Descriptor file;
  while ((file.fd = open(path.c_str(), O_RDONLY | O_CLOEXEC)) < 0) {
    if (errno != EINTR)
      throw InputError(path + ": cannot open " + the_noun + ": " + std::strerror(errno));
    if (stop.Requested()) throw interrupted();
  }
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    if (stop.Requested()) throw interrupted();
    const ssize_t got = read(file.fd, buffer, sizeof buffer);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw InputError(path + ": cannot read " + the_noun + ": " + std::strerror(errno));
    }
    if (got == 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
    if (text.size() > limit)
      throw InputError(path + ": " + the_noun + " is larger than " + std::to_string(limit >> 20) +
                       " MiB (the limit)");
  }
  return text;
}

}  // namespace screwfem::io_detail
