#include "rubdyn/io/text_files.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <stdexcept>

namespace rubdyn {

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted) {
      if (ch == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (ch == '"') {
        quoted = false;
      } else {
        cur += ch;
      }
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (ch != '\r') {
      cur += ch;
    }
  }
  out.push_back(cur);
  return out;
}

namespace {

/// The length of the valid UTF-8 sequence at text[i] (0: none there).
std::size_t utf8_length(std::string_view text, std::size_t i) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  std::size_t n = 0;
  unsigned lo = 0x80, hi = 0xBF;  // the range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;  // overlong
    if (c == 0xED) hi = 0x9F;  // surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;  // overlong
    if (c == 0xF4) hi = 0x8F;  // above U+10FFFF
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  if (b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (b(i + k) < 0x80 || b(i + k) > 0xBF) return 0;
  return n;
}

}  // namespace

bool valid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_length(text, i);
    if (n == 0) return false;
    i += n;
  }
  return true;
}

std::string printable_text(std::string_view text, std::size_t max_chars) {
  std::string out;
  std::size_t chars = 0;
  for (std::size_t i = 0; i < text.size(); ++chars) {
    if (chars == max_chars) return out + "...";
    const unsigned char c = static_cast<unsigned char>(text[i]);
    const std::size_t n = utf8_length(text, i);
    if (n == 0 || c < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02X}", static_cast<unsigned>(c));
      ++i;
    } else {
      out.append(text.substr(i, n));
      i += n;
    }
  }
  return out;
}

double input_pipe_wait() {
  static const double seconds = [] {
    if (const char* w = std::getenv("RUBDYN_PIPE_WAIT")) {
      char* end = nullptr;
      const double v = std::strtod(w, &end);
      if (end != w && *end == '\0' && v >= 0.01 && v <= 3600.0) return v;
    }
    return 10.0;
  }();
  return seconds;
}

namespace {

/// Reads a FIFO (a named pipe, or a shell's process substitution <(...)) to its end, at most
/// max_bytes + 1 bytes, waiting at most `wait` seconds in all for its writer. The descriptor
/// is non-blocking: a FIFO without a writer gives EOF (read 0) or EAGAIN at once, so that poll
/// does the waiting, with the time left.
std::string read_fifo(int fd, std::size_t max_bytes, double wait, std::string_view role,
                      const std::function<void(const std::string&)>& refuse) {
  using clock = std::chrono::steady_clock;
  const auto deadline = clock::now() + std::chrono::duration<double>(wait);
  std::string text;
  char buf[65536];
  bool data = false;
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
      text.append(buf, static_cast<std::size_t>(n));
      data = true;
      if (text.size() > max_bytes) return text;  // (refused by the caller)
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN)
      refuse(fmt::format("cannot read the {} file: {}", role, std::strerror(errno)));
    if (n == 0 && data) return text;  // end of file: every writer closed after writing
    // nothing yet: no writer (read 0) or a writer that has not written (EAGAIN)
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
    struct pollfd p {};
    p.fd = fd;
    p.events = POLLIN;
    const int r = left > 0 ? ::poll(&p, 1, static_cast<int>(left)) : 0;
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) refuse(fmt::format("cannot read the {} file: {}", role, std::strerror(errno)));
    if (r == 0)
      refuse(fmt::format(
          "is a FIFO (named pipe) from which {} within {:g} s (no writer, or a slow one; "
          "RUBDYN_PIPE_WAIT sets the wait in seconds)",
          data ? "the rest did not arrive" : "nothing arrived", wait));
    if ((p.revents & POLLHUP) && !(p.revents & POLLIN)) return text;  // a writer came and went
  }
}

}  // namespace

std::string read_input_file(const std::string& path, std::size_t max_bytes, std::string_view role) {
  auto refuse = [](const std::string& why) { throw InputRefused(why); };
  auto cannot = [&](int err) {
    return fmt::format("cannot read the {} file: {}", role, std::strerror(err));
  };
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) refuse(cannot(errno));
  // (closed on every way out, a refusal's exception included)
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) refuse(cannot(errno));
  std::string text;
  if (S_ISFIFO(st.st_mode)) {
    text = read_fifo(fd, max_bytes, input_pipe_wait(), role, refuse);
  } else if (!S_ISREG(st.st_mode)) {
    refuse(S_ISDIR(st.st_mode)    ? fmt::format("is a directory, not a {} file", role)
           : S_ISSOCK(st.st_mode) ? "is a socket, not a regular file: not read"
                                  : "is a device, not a regular file: not read");
  } else {
    // what the file holds, as fstat says: no more is allocated or zero-filled (a file that
    // grows while it is read is read on, in steps, up to max_bytes + 1 bytes)
    const std::size_t size = static_cast<std::size_t>(std::max<off_t>(st.st_size, 0));
    text.resize(std::min(size, max_bytes) + 1);
    std::size_t got = 0;
    for (;;) {
      if (got == text.size()) {
        if (text.size() > max_bytes) break;
        text.resize(std::min(std::max(2 * text.size(), std::size_t{4096}), max_bytes + 1));
      }
      const ssize_t n = ::read(fd, text.data() + got, text.size() - got);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) refuse(cannot(errno));
      if (n == 0) break;
      got += static_cast<std::size_t>(n);
    }
    text.resize(got);
  }
  if (text.size() > max_bytes)
    refuse(fmt::format("a file larger than {} bytes: not a {} file", max_bytes, role));
  return text;
}

std::string quoted_string(std::string_view text) {
  std::string out = "\"";
  for (const char ch : text) {
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) {
          out += fmt::format("\\u{:04X}", static_cast<unsigned>(static_cast<unsigned char>(ch)));
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

std::string cut_row_warning(const std::string& file, long line) {
  return fmt::format(
      "{}:{}: the last row has no line end (the run was cut short while writing it): ignored", file,
      line);
}

namespace {

std::string reason(int err) {
  return err ? std::strerror(err) : "write failed (no reason given)";
}

[[noreturn]] void cannot(const std::string& shown, int err) {
  throw OutputError(fmt::format("cannot write {}: {}", shown, reason(err)));
}

[[noreturn]] void refuse(const std::string& shown, const std::string& why) {
  throw PathRefused(fmt::format("cannot write {}: {}", shown, why));
}

bool same_file(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

/// The path is the file the standard output goes to.
bool is_stdout(const struct stat& st) {
  struct stat out {};
  return ::fstat(STDOUT_FILENO, &out) == 0 && same_file(st, out);
}

/// How a path is written (the rule in text_files.hpp).
enum class Way { Replace, Through, Stdout };

/// What `name` is, by the rule; refusals thrown. Opens nothing.
Way classify(int dir_fd, const std::string& name, const std::string& shown) {
  if (name.empty()) refuse("''", "an empty path");
  struct stat l {};
  if (::fstatat(dir_fd, name.c_str(), &l, AT_SYMLINK_NOFOLLOW) != 0) {
    if (errno == ENOENT) return Way::Replace;  // created (a missing parent fails at the open)
    cannot(shown, errno);
  }
  struct stat f {};
  if (::fstatat(dir_fd, name.c_str(), &f, 0) != 0) {
    if (S_ISLNK(l.st_mode) && errno == ENOENT)
      refuse(shown,
             "a symbolic link to a missing file (rubdyn never replaces a link: create "
             "the file it names, or remove the link)");
    cannot(shown, errno);
  }
  if (S_ISDIR(f.st_mode)) refuse(shown, "a directory");
  if (S_ISBLK(f.st_mode)) refuse(shown, "a block device (rubdyn does not write onto disks)");
  if (is_stdout(f)) return Way::Stdout;
  if (S_ISLNK(l.st_mode) || !S_ISREG(f.st_mode)) return Way::Through;
  return Way::Replace;
}

/// Opens a device, FIFO, socket or the file behind a link for writing through it: never
/// created, never replaced, never waited for (a FIFO without a reader is refused).
int open_through(int dir_fd, const std::string& name, const std::string& shown) {
  const int fd = ::openat(dir_fd, name.c_str(), O_WRONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENXIO) refuse(shown, "a FIFO without a reader, or a socket");
    cannot(shown, errno);
  }
  struct stat st {};
  const int flags = ::fcntl(fd, F_GETFL);
  if (::fstat(fd, &st) != 0 || flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0 ||
      (S_ISREG(st.st_mode) && ::ftruncate(fd, 0) != 0)) {
    const int err = errno;
    ::close(fd);
    cannot(shown, err);
  }
  return fd;
}

/// Writes all of `text` to `fd`: 0, or the errno of the failed write (EIO when none is given).
int write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 && errno ? errno : EIO;
    done += static_cast<std::size_t>(n);
  }
  return 0;
}

}  // namespace

void write_file_at(int dir_fd, const std::string& name, const std::string& shown,
                   const std::string& text) {
  switch (classify(dir_fd, name, shown)) {
    case Way::Stdout:
      errno = 0;
      if (std::fflush(stdout) != 0) cannot(shown, errno);
      if (const int err = write_all(STDOUT_FILENO, text)) cannot(shown, err);
      return;
    case Way::Through: {
      const int fd = open_through(dir_fd, name, shown);
      int err = write_all(fd, text);
      if (::close(fd) != 0 && err == 0) err = errno ? errno : EIO;
      if (err != 0) cannot(shown, err);
      return;
    }
    case Way::Replace: break;
  }
  // Every step checked, close included (a full disk may show only there). The temporary file
  // is created afresh (O_EXCL, O_NOFOLLOW): a link or a FIFO of that name is never written.
  const std::string tmp = name + ".tmp";
  if (::unlinkat(dir_fd, tmp.c_str(), 0) != 0 && errno != ENOENT) cannot(shown + ".tmp", errno);
  const int fd =
      ::openat(dir_fd, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) cannot(shown + ".tmp", errno);
  int err = write_all(fd, text);
  if (::close(fd) != 0 && err == 0) err = errno ? errno : EIO;
  if (err != 0) {
    ::unlinkat(dir_fd, tmp.c_str(), 0);
    cannot(shown, err);
  }
  if (::renameat(dir_fd, tmp.c_str(), dir_fd, name.c_str()) != 0) {
    err = errno;
    ::unlinkat(dir_fd, tmp.c_str(), 0);
    throw OutputError(fmt::format("cannot rename {}.tmp to {}: {}", shown, shown, reason(err)));
  }
}

void write_file_atomic(const std::string& path, const std::string& text) {
  write_file_at(AT_FDCWD, path, path, text);
}

std::FILE* open_output_stream_at(int dir_fd, const std::string& name, const std::string& shown) {
  int fd = -1;
  switch (classify(dir_fd, name, shown)) {
    case Way::Stdout:
      errno = 0;
      if (std::fflush(stdout) != 0) cannot(shown, errno);
      fd = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 0);
      break;
    case Way::Through: fd = open_through(dir_fd, name, shown); break;
    case Way::Replace:
      fd = ::openat(dir_fd, name.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC,
                    0666);
      break;
  }
  if (fd < 0) cannot(shown, errno);
  std::FILE* f = ::fdopen(fd, "w");
  if (!f) {
    const int err = errno;
    ::close(fd);
    cannot(shown, err);
  }
  return f;
}

void check_output_path(const std::string& path) {
  (void)classify(AT_FDCWD, path, path);
}

}  // namespace rubdyn
