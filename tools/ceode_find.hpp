// ceode-stability find: the parameter-set finder (docs/stability.md, "High-degree sets").
#ifndef CEODE_TOOLS_CEODE_FIND_HPP_
#define CEODE_TOOLS_CEODE_FIND_HPP_

namespace ceode_tools {

// argv[0] is "find"; returns the process exit code.
int FindMain(int argc, char** argv);

}  // namespace ceode_tools

#endif  // CEODE_TOOLS_CEODE_FIND_HPP_
