// A shared library opened at run time (dlopen), for the optional ones: OSMesa (--gl osmesa,
// context_osmesa.cpp) and Xlib (--window, render_client/x11_lib.cpp). The binaries link neither,
// so they start on a machine with only EGL (a GPU driver and libglvnd); asking for the missing
// one gives one error naming it. Header-only: the window test uses it without occ_gl.
#pragma once
#include <dlfcn.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace occ {

class DynamicLibrary {
 public:
  // Opens $env_var when it is set and not empty (a path or a file name; a path that does not
  // exist makes the library unloadable, for tests), else `soname`. Throws std::runtime_error
  // "cannot load <what> <file>[ ($env_var)]: <dlerror>; <hint>" when that fails. The library stays
  // loaded for the process's lifetime (the objects made with it may outlive any owner).
  DynamicLibrary(const std::string& what, const char* soname, const char* env_var, const std::string& hint) {
    const char* env = std::getenv(env_var);
    const bool from_env = env && *env;
    const std::string file = from_env ? env : soname;
    handle_ = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) {
      const char* why = dlerror();
      throw std::runtime_error("cannot load " + what + " " + file + (from_env ? std::string(" (") + env_var + ")" : "") +
                               ": " + (why ? why : "dlopen failed") + "; " + hint);
    }
    name_ = what + " " + file;
  }

  // The entry point `name` as a function pointer of type F; throws naming it when it is missing.
  template <class F>
  F symbol(const char* name) const {
    void* p = dlsym(handle_, name);
    if (!p) throw std::runtime_error(name_ + " has no " + name);
    return reinterpret_cast<F>(p);
  }

 private:
  void* handle_ = nullptr;
  std::string name_;
};

}  // namespace occ
