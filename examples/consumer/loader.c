/* Loads an app as a shared object and runs its entry point, the way cFS's executive loads an app
 * on Linux (dlopen, then dlsym of the entry point named in its start-up script): the
 * shared-object consumer of tools/check-install. The app (examples/consumer/main.c built as
 * a shared object, its main renamed ccmap_app_main) links the position-independent ccmap core
 * archives into itself; this program links neither ccmap nor libstdc++.
 *
 *   loader <app.so> <entry point>      exit status: the entry point's (2: not loaded) */
#include <dlfcn.h>
#include <stdio.h>

int main(int argc, char** argv) {
  void* app;
  void* symbol;
  int (*entry)(void);
  int status;
  if (argc != 3) {
    fprintf(stderr, "usage: loader <app.so> <entry point>\n");
    return 2;
  }
  app = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
  if (app == NULL) {
    fprintf(stderr, "loader: dlopen: %s\n", dlerror());
    return 2;
  }
  symbol = dlsym(app, argv[2]);
  if (symbol == NULL) {
    fprintf(stderr, "loader: dlsym %s: %s\n", argv[2], dlerror());
    dlclose(app);
    return 2;
  }
  *(void**)(&entry) = symbol; /* POSIX: a function pointer from dlsym */
  status = entry();
  dlclose(app);
  return status;
}
