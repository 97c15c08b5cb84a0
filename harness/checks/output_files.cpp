#include "harness/checks/output_files.hpp"

#include "lexdyn/common/error.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>

namespace lexdyn::files {

namespace fs = std::filesystem;

std::string reason(int err) { return std::strerror(err); }

namespace {

// Writes all of [data, data + n) to fd; false with errno set on failure.
bool writeAll(int fd, const char* data, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

// fsync of the folder that holds PATH, so that a rename survives a crash of the machine. Some
// file systems refuse fsync on a folder (EINVAL): that is not a failure.
void syncFolderOf(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  const int fd = ::open(parent.empty() ? "." : parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
    const int err = errno;
    ::close(fd);
    throw OutputError(parent.string(), "cannot sync the folder: " + reason(err));
  }
  ::close(fd);
}

std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string holderLine(const std::string& command) {
  char host[256] = {0};
  if (::gethostname(host, sizeof(host) - 1) != 0) std::strcpy(host, "unknown");
  return "pid=" + std::to_string(::getpid()) + " started=" + utcNow() + " host=" + host + " command=" + command + "\n";
}

// "pid 1234, lexdyn-harness run, started 2026-11-28T07:01:02Z on HOST" from a lock file's line.
std::string describeHolder(int fd) {
  char buf[1024];
  const ssize_t n = ::pread(fd, buf, sizeof(buf) - 1, 0);
  if (n <= 0) return "holder unknown";
  std::string line(buf, static_cast<size_t>(n));
  line = line.substr(0, line.find('\n'));
  auto field = [&](const std::string& key, bool rest) -> std::string {
    const std::string k = key + "=";
    size_t p = line.rfind(k, 0) == 0 ? 0 : line.find(" " + k);
    if (p == std::string::npos) return "";
    p += p == 0 ? k.size() : k.size() + 1;
    return rest ? line.substr(p) : line.substr(p, line.find(' ', p) - p);
  };
  const std::string pid = field("pid", false), started = field("started", false), host = field("host", false),
                    command = field("command", true);
  if (pid.empty()) return "holder unknown";
  return "pid " + pid + (command.empty() ? "" : ", " + command) + (started.empty() ? "" : ", started " + started) +
         (host.empty() ? "" : " on " + host);
}

// Opens DIR/.lexdyn.lock (or FILE.lock), created when missing.
int openLockFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw OutputError(path, "cannot open the lock file: " + reason(errno));
  return fd;
}

void recordHolder(int fd, const std::string& command) {
  const std::string line = holderLine(command);
  // Best effort: the lock is the flock, the line only names its holder for others' messages.
  if (::ftruncate(fd, 0) == 0) (void)!::pwrite(fd, line.data(), line.size(), 0);
}

}  // namespace

void createFolder(const std::string& dir) {
  if (dir.empty()) throw InputError("--out", "expected a folder, found an empty path");
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  // The first existing ancestor that is not a folder makes this a bad path, not a system failure.
  for (fs::path p = fs::path(dir); !p.empty(); p = p.parent_path()) {
    std::error_code e2;
    const fs::file_status st = fs::status(p, e2);
    if (fs::exists(st)) {
      if (!fs::is_directory(st)) throw InputError(dir, "cannot create the output folder: " + p.string() + " exists and is not a folder");
      break;
    }
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(dir, "cannot create the output folder: " + ec.message());
  if (!fs::is_directory(dir, ec)) throw OutputError(dir, "cannot create the output folder");
}

void writeAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".partial";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw OutputError(tmp, "cannot open for writing: " + reason(errno));
  auto fail = [&](const char* what) {
    const int err = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw OutputError(tmp, std::string(what) + ": " + reason(err));
  };
  if (!writeAll(fd, text.data(), text.size())) fail("cannot write");
  if (::fsync(fd) != 0 && errno != EINVAL) fail("cannot sync");
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw OutputError(tmp, "cannot write: " + reason(err));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw OutputError(path, "cannot rename into place: " + reason(err));
  }
  syncFolderOf(path);
}

void appendDurably(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw OutputError(path, "cannot open for appending: " + reason(errno));
  const bool ok = writeAll(fd, text.data(), text.size()) && (::fsync(fd) == 0 || errno == EINVAL);
  const int err = errno;
  ::close(fd);
  if (!ok) throw OutputError(path, "cannot append: " + reason(err));
}

std::optional<std::string> readWhole(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::string out;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof(buf));
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      return std::nullopt;
    }
    if (n == 0) break;
    out.append(buf, static_cast<size_t>(n));
  }
  ::close(fd);
  return out;
}

FolderLock::FolderLock(const std::string& dir, const std::string& command, Mode mode) {
  createFolder(dir);
  const std::string path = (fs::path(dir) / kLockFileName).string();
  const int fd = openLockFile(path);
  if (::flock(fd, (mode == Mode::kShared ? LOCK_SH : LOCK_EX) | LOCK_NB) != 0) {
    const int err = errno;
    if (err != EWOULDBLOCK) {
      ::close(fd);
      throw OutputError(path, "cannot lock: " + reason(err));
    }
    const std::string holder = describeHolder(fd);
    ::close(fd);
    throw InputError(dir, "in use by another lexdyn job (" + holder + "); wait for it to end or give another --out");
  }
  recordHolder(fd, command);
  fd_ = fd;
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the flock
}

FolderLock::FolderLock(FolderLock&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }

FolderLock& FolderLock::operator=(FolderLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

FileLock::FileLock(const std::string& file, const std::string& command, const std::atomic<int>* interrupt) {
  const fs::path parent = fs::path(file).parent_path();
  if (!parent.empty()) createFolder(parent.string());
  const std::string path = file + ".lock";
  fd_ = openLockFile(path);
  // Polled, so that a signal (whose handler restarts a blocking flock) ends the wait.
  while (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK || errno == EINTR) {
      if (interrupt != nullptr && interrupt->load() != 0) {
        ::close(fd_);
        fd_ = -1;
        return;
      }
      ::usleep(20000);
      continue;
    }
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw OutputError(path, "cannot lock: " + reason(err));
  }
  recordHolder(fd_, command);
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace lexdyn::files
