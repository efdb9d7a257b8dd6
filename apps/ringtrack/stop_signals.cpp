#include "stop_signals.hpp"

#include <csignal>

namespace ringtrack::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
struct sigaction g_previous_int {};
struct sigaction g_previous_term {};

extern "C" void on_stop_signal(int signal_number) {
  g_signal.store(signal_number);
  g_stop.store(true);
}

void install(int signal_number, struct sigaction& previous) {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: the second Ctrl-C or SIGTERM ends the process at once, as without a handler.
  // No SA_RESTART: a blocking read returns EINTR and the command notices the flag.
  action.sa_flags = SA_RESETHAND;
  sigaction(signal_number, &action, &previous);
}

}  // namespace

StopSignals::StopSignals() {
  g_stop.store(false);
  g_signal.store(0);
  install(SIGINT, g_previous_int);
  install(SIGTERM, g_previous_term);
}

StopSignals::~StopSignals() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
}

const std::atomic<bool>& StopSignals::stop_flag() {
  return g_stop;
}

std::string StopSignals::signal_name() {
  switch (g_signal.load()) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return {};
  }
}

}  // namespace ringtrack::cli
