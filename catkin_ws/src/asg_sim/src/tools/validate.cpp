// asg_sim_validate FILE...: loads each scenario YAML with the simulator's own loader and
// validator and prints "OK FILE" or "ERROR FILE: reason" (one line; newlines in the reason become
// " | "). Exit status: 0 every file valid, 1 some refused, 2 no file given. A crash (a signal) is
// a bug: the fuzzing harness (tests/fuzz_inputs.py) runs thousands of mutated files through it.
#include <cstdio>
#include <exception>
#include <string>

#include "asg_sim/scene_yaml.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: asg_sim_validate FILE...\n");
    return 2;
  }
  int refused = 0;
  for (int i = 1; i < argc; ++i) {
    try {
      asg_sim::ScenarioFile f = asg_sim::loadScenarioYaml(argv[i]);
      asg_sim::validateScene(f.spec);
      std::printf("OK %s\n", argv[i]);
    } catch (const std::exception& e) {
      std::string why = e.what();
      for (size_t p = why.find('\n'); p != std::string::npos; p = why.find('\n', p)) why.replace(p, 1, " | ");
      std::printf("ERROR %s: %s\n", argv[i], why.c_str());
      ++refused;
    }
  }
  return refused ? 1 : 0;
}
