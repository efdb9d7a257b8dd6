#include "plots.hpp"

#include <cstdlib>
#include <iostream>

#include "data_dirs.hpp"

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;

// One shell word, whatever the path holds.
std::string quote(const std::string& s) {
  std::string q(1, '\'');
  for (const char ch : s) {
    if (ch == '\'') {
      q.append("'\\''");
    } else {
      q.push_back(ch);
    }
  }
  q.push_back('\'');
  return q;
}

}  // namespace

bool run_plot_script(const std::string& script_name, const std::vector<fs::path>& args) {
  const fs::path script = scripts_dir() / script_name;
  const char* python = "/usr/bin/python3";
  if (!fs::exists(python) || !fs::exists(script)) {
    std::cerr << "ringtrack: warning: no plot: " << (fs::exists(python) ? script.string() : python)
              << " not found\n";
    return false;
  }
  if (std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") != 0) {
    std::cerr << "ringtrack: warning: no plot: python3-matplotlib or python3-numpy is not "
                 "installed (apt-get install python3-matplotlib python3-numpy)\n";
    return false;
  }
  std::string cmd = std::string(python) + " " + quote(script.string());
  for (const auto& a : args) {
    cmd.push_back(' ');
    cmd.append(quote(a.string()));
  }
  if (std::system(cmd.c_str()) != 0) {
    std::cerr << "ringtrack: warning: the plot script failed: " << cmd << "\n";
    return false;
  }
  return true;
}

}  // namespace ringtrack::cli
