// Writing the harness's outputs safely (docs/architecture.md, "Faults"): whole files written
// atomically and durably, output folders locked against a second job, the operating system's
// reason in every failure (lexdyn::OutputError, exit code 3).
#pragma once

#include <optional>
#include <atomic>
#include <string>

namespace lexdyn::files {

/// strerror(err) as a string.
std::string reason(int err);

/// Creates DIR and its parents. InputError when DIR (or a parent) exists and is not a folder
/// (a bad --out); OutputError with the reason when the system refuses (permissions, a full or
/// read-only file system).
void createFolder(const std::string& dir);

/// Writes TEXT to PATH: to PATH.partial, fsync, rename, fsync of the folder, so that PATH is
/// either the old file or the whole new one, also after a crash of the machine. OutputError
/// with the operating system's reason at the first failure (the partial file is removed).
void writeAtomically(const std::string& path, const std::string& text);

/// Appends TEXT (whole lines) to PATH and fsyncs it. OutputError with the reason.
void appendDurably(const std::string& path, const std::string& text);

/// The whole file, or nullopt when it does not exist or cannot be read.
std::optional<std::string> readWhole(const std::string& path);

/// An advisory lock on an output folder, held for the lifetime of the object: the file
/// DIR/.lexdyn.lock, locked with flock(2) and holding one line `pid=P started=T host=H
/// command=C` of its holder. A lock of a process that ended is free (the kernel releases it),
/// so a stale file is taken over. The file is never removed (a third job would lock a new one).
class FolderLock {
 public:
  enum class Mode { kExclusive, kShared };
  FolderLock() = default;
  /// Creates DIR (createFolder) and takes its lock without waiting. When another job holds it:
  /// InputError (exit code 2) "DIR: in use by another lexdyn job (pid P, C, started T on H);
  /// wait for it to end or give another --out". Shared locks (a Slurm array's tasks writing
  /// disjoint points of one sweep) exclude exclusive ones only.
  FolderLock(const std::string& dir, const std::string& command, Mode mode = Mode::kExclusive);
  ~FolderLock();
  FolderLock(FolderLock&& o) noexcept;
  FolderLock& operator=(FolderLock&& o) noexcept;
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

/// A lock on one file shared by many jobs (the sweeps' failure database, a history), waited
/// for: FILE.lock, the same format as FolderLock's.
class FileLock {
 public:
  /// Waits for the lock; with `interrupt`, gives up when it becomes nonzero (a signal asked the
  /// job to stop): held() is then false.
  FileLock(const std::string& file, const std::string& command, const std::atomic<int>* interrupt = nullptr);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

/// The name of the lock file in a locked folder.
constexpr const char* kLockFileName = ".lexdyn.lock";

}  // namespace lexdyn::files
