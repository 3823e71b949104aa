// The virtual MCU: the firmware core as a Linux process speaking the protocol on a serial device path.
//
//   mantaray-vmcu --port /dev/ttyUSB0     open an existing serial device (or a pty slave someone made)
//   mantaray-vmcu --pty /tmp/mantaray     create a pty and symlink its slave there for the host to open (replacing
//                                         only a link to a pty, such as one an earlier run left)
//   --clock wall|sim                      wall clock (default) or the simulated clock set by sim_clock
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include "firmware.h"    // Firmware
#include "native_hal.h"  // NativeHal

namespace {

volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void usage(const char* argv0) {
  fprintf(stderr,
          "usage: %s (--port PATH | --pty LINK) [--clock wall|sim]\n"
          "  --port PATH   open an existing serial device path (115200 8N1, raw)\n"
          "  --pty LINK    create a pseudo-terminal and symlink its slave to LINK\n"
          "  --clock MODE  wall: the process's monotonic clock (default); sim: time moves only\n"
          "                by sim_clock messages, for lock-step simulation\n",
          argv0);
}

bool make_raw(int fd) {
  termios tio;
  if (tcgetattr(fd, &tio) != 0) return false;
  cfmakeraw(&tio);
  cfsetispeed(&tio, B115200);
  cfsetospeed(&tio, B115200);
  return tcsetattr(fd, TCSANOW, &tio) == 0;
}

// Writes a whole buffer, waiting for room if the reader is slow (a pty holds a few KB); a stop ends the wait.
bool write_all(int fd, const uint8_t* data, size_t len) {
  while (len > 0 && !g_stop) {
    const ssize_t n = write(fd, data, len);
    if (n > 0) {
      data += n;
      len -= static_cast<size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      pollfd p{fd, POLLOUT, 0};
      poll(&p, 1, 100);
    } else {
      return false;
    }
  }
  return true;
}

// Whether the pty's link may go at path: nothing is there, or a symlink to a pty (live, or left by a run that was
// killed). Anything else there is the user's and stays: unlink() is never called on it.
bool link_replaceable(const char* path) {
  struct stat st;
  if (lstat(path, &st) != 0) return true;  // nothing there (or out of reach: symlink() then says why)
  if (!S_ISLNK(st.st_mode)) return false;
  char target[64];
  const ssize_t n = readlink(path, target, sizeof target - 1);
  if (n < 0) return false;
  target[n] = '\0';
  return strncmp(target, "/dev/pts/", 9) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  const char* port = nullptr;
  const char* link = nullptr;
  mr::proto::Clock clock = mr::proto::Clock::kWall;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!strcmp(argv[i], "--port") && has_value) {
      port = argv[++i];
    } else if (!strcmp(argv[i], "--pty") && has_value) {
      link = argv[++i];
    } else if (!strcmp(argv[i], "--clock") && has_value) {
      const char* mode = argv[++i];
      if (!strcmp(mode, "wall")) {
        clock = mr::proto::Clock::kWall;
      } else if (!strcmp(mode, "sim")) {
        clock = mr::proto::Clock::kSimulated;
      } else {
        fprintf(stderr, "error: --clock must be wall or sim, not '%s'\n", mode);
        return 2;
      }
    } else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      usage(argv[0]);
      return 0;
    } else {
      fprintf(stderr, "error: unexpected argument '%s'\n", argv[i]);
      usage(argv[0]);
      return 2;
    }
  }
  if ((port == nullptr) == (link == nullptr)) {
    fprintf(stderr, "error: give exactly one of --port and --pty\n");
    usage(argv[0]);
    return 2;
  }

  int fd = -1;
  int slave_keepalive = -1;  // our own handle on the pty slave, so the master never sees a hang-up
  if (port != nullptr) {
    fd = open(port, O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
      fprintf(stderr, "error: cannot open %s: %s\n", port, strerror(errno));
      return 1;
    }
    if (!make_raw(fd)) {
      fprintf(stderr, "error: %s is not a serial device (termios: %s)\n", port, strerror(errno));
      return 1;
    }
  } else {
    if (!link_replaceable(link)) {
      fprintf(stderr, "error: --pty %s: it exists and is not a link to a pty; not replacing it\n", link);
      return 2;
    }
    fd = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0 || grantpt(fd) != 0 || unlockpt(fd) != 0) {
      fprintf(stderr, "error: cannot create a pty: %s\n", strerror(errno));
      return 1;
    }
    const char* slave = ptsname(fd);
    slave_keepalive = open(slave, O_RDWR | O_NOCTTY);
    if (slave_keepalive < 0 || !make_raw(slave_keepalive)) {
      fprintf(stderr, "error: cannot set up pty %s: %s\n", slave, strerror(errno));
      return 1;
    }
    unlink(link);
    if (symlink(slave, link) != 0) {
      fprintf(stderr, "error: cannot create symlink %s -> %s: %s\n", link, slave, strerror(errno));
      return 1;
    }
  }

  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  signal(SIGPIPE, SIG_IGN);

  mr::NativeHal hal(clock);
  mr::Firmware firmware(hal);
  firmware.boot(mr::proto::ResetCause::kPowerOn);

  int status = 0;
  uint8_t buf[256];
  while (!g_stop) {
    size_t n;
    while (!g_stop && (n = hal.take_tx(buf, sizeof buf)) > 0) {
      if (!write_all(fd, buf, n)) {
        fprintf(stderr, "error: write to the serial device failed: %s\n", strerror(errno));
        status = 1;
        g_stop = 1;
      }
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = poll(&p, 1, 1);  // [ms] the longest a wall-clock deadman check waits
    if (ready > 0 && (p.revents & POLLIN)) {
      const ssize_t got = read(fd, buf, sizeof buf);
      for (ssize_t i = 0; i < got; ++i) firmware.rx_byte(buf[i]);
      if (got == 0 || (got < 0 && errno != EAGAIN && errno != EINTR)) break;  // the device went away
    } else if (ready > 0 && (p.revents & (POLLHUP | POLLERR))) {
      break;
    }
    firmware.poll();
  }
  if (link != nullptr) unlink(link);
  if (slave_keepalive >= 0) close(slave_keepalive);
  close(fd);
  return status;
}
