/* MuJoCo's side of bench/peers.py: whole steps and forward evaluations, timed on request.
 *
 *   mujoco_probe NAME=MODEL.xml...
 *
 * Loads every model (MJCF written by bench/peers.py: the URDF robots with RK4 at 1 ms, no
 * geometry and no joint limits; the rows of four-bars with their closing `connect` equalities),
 * starts each from its first keyframe when it has one, prints
 *   ready NAME/step NAME/forward ...
 * then answers each line `CASE CALLS` of its standard input with the CPU time, in seconds, that
 * this thread spent on CALLS calls of CASE: `step` is mj_step (the integrator of the model's
 * options), `forward` is mj_forward at the starting state (every stage of one evaluation, the
 * constraint solve included). Steps go on from where the last batch left them, and start again
 * from the keyframe every 1,000 steps so the state stays where it started (no blow-up). */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mujoco/mujoco.h>

#define MAX_MODELS 64

typedef struct {
  char name[256];
  mjModel *model;
  mjData *data;
  long steps;
} Entry;

static double thread_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void start(Entry *e) {
  if (e->model->nkey > 0) {
    mj_resetDataKeyframe(e->model, e->data, 0);
  } else {
    mj_resetData(e->model, e->data);
  }
  mj_forward(e->model, e->data);
}

int main(int argc, char **argv) {
  static Entry entries[MAX_MODELS];
  int count = 0;
  char error[1000];
  printf("ready");
  for (int k = 1; k < argc && count < MAX_MODELS; ++k) {
    const char *equal = strchr(argv[k], '=');
    if (!equal || (size_t)(equal - argv[k]) >= sizeof entries[0].name) {
      fprintf(stderr, "usage: %s NAME=MODEL.xml...\n", argv[0]);
      return 2;
    }
    Entry *e = &entries[count];
    memcpy(e->name, argv[k], (size_t)(equal - argv[k]));
    e->name[equal - argv[k]] = '\0';
    e->model = mj_loadXML(equal + 1, NULL, error, sizeof error);
    if (!e->model) {
      fprintf(stderr, "error: MuJoCo cannot load `%s`: %s\n", equal + 1, error);
      return 1;
    }
    e->data = mj_makeData(e->model);
    e->steps = 0;
    start(e);
    printf(" %s/step %s/forward", e->name, e->name);
    ++count;
  }
  printf("\n");
  fflush(stdout);

  char line[1024];
  double checksum = 0.0;
  while (fgets(line, sizeof line, stdin)) {
    char which[512];
    long calls = 0;
    if (sscanf(line, "%511s %ld", which, &calls) != 2 || calls <= 0) {
      printf("error: expected `CASE CALLS`\n");
      fflush(stdout);
      continue;
    }
    char *slash = strrchr(which, '/');
    Entry *e = NULL;
    if (slash) {
      *slash = '\0';
      for (int k = 0; k < count; ++k)
        if (strcmp(entries[k].name, which) == 0) e = &entries[k];
    }
    const int step = slash && strcmp(slash + 1, "step") == 0;
    const int forward = slash && strcmp(slash + 1, "forward") == 0;
    if (!e || !(step || forward)) {
      printf("error: no case `%s`\n", which);
      fflush(stdout);
      continue;
    }
    double begin, spent = 0.0;
    if (step) {
      begin = thread_seconds();
      for (long i = 0; i < calls; ++i) {
        if (e->steps % 1000 == 0) {
          /* Back to the start, outside the timed steps. */
          spent += thread_seconds() - begin;
          start(e);
          begin = thread_seconds();
        }
        mj_step(e->model, e->data);
        ++e->steps;
      }
      spent += thread_seconds() - begin;
      checksum += e->data->qpos[0];
    } else {
      start(e);
      begin = thread_seconds();
      for (long i = 0; i < calls; ++i) {
        mj_forward(e->model, e->data);
        checksum += e->data->qacc[0];
      }
      spent = thread_seconds() - begin;
    }
    if (checksum != checksum) fprintf(stderr, "warning: a result was not finite\n");
    printf("%.9e\n", spent);
    fflush(stdout);
  }
  for (int k = 0; k < count; ++k) {
    mj_deleteData(entries[k].data);
    mj_deleteModel(entries[k].model);
  }
  return 0;
}
