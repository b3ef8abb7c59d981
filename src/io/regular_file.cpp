#include "delta/io/regular_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <system_error>

#include "delta/core/error.h"

namespace delta::io {
namespace {

std::string systemReason(int error) {
  return std::generic_category().message(error);
}

const char* fileTypeName(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

RegularFile::RegularFile(const std::filesystem::path& path) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
  descriptor_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (descriptor_ < 0) {
    const int error = errno;
    if (error == ENOENT) throw Error("no such file");
    throw Error("cannot open it for reading: " + systemReason(error));
  }
  struct stat status {};
  if (::fstat(descriptor_, &status) != 0) {
    const int error = errno;
    ::close(descriptor_);
    throw Error("cannot read its status: " + systemReason(error));
  }
  if (!S_ISREG(status.st_mode)) {
    ::close(descriptor_);
    if (S_ISDIR(status.st_mode)) throw Error("it is a directory, not a file");
    throw Error(std::string("it is ") + fileTypeName(status.st_mode) +
                ", not a regular file: only regular files are read");
  }
  size_ = static_cast<std::uintmax_t>(status.st_size);
}

RegularFile::~RegularFile() {
  ::close(descriptor_);
}

std::string RegularFile::read(std::uintmax_t offset, std::uintmax_t count) const {
  if (offset >= size_) return {};
  if (count > size_ - offset) count = size_ - offset;
  std::string bytes(static_cast<std::size_t>(count), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t got = ::pread(descriptor_, bytes.data() + done, bytes.size() - done,
                                static_cast<off_t>(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      throw Error("reading failed: " + systemReason(errno));
    }
    if (got == 0) break;  // the file shrank since it was opened
    done += static_cast<std::size_t>(got);
  }
  bytes.resize(done);
  return bytes;
}

std::string readSmallRegularFile(const std::filesystem::path& path, std::uintmax_t limit,
                                 const std::string& what) {
  const RegularFile file(path);
  if (file.size() > limit)
    throw Error("it has " + std::to_string(file.size()) + " bytes; " + what + " may have at most " +
                std::to_string(limit));
  return file.readAll();
}

}  // namespace delta::io
