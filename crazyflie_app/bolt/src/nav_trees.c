/*
 * The detected-tree memory T_d and the visited list (the port of tree_memory.py), bounded, keyed by
 * stable ids (never by array position: removing one tree cannot retarget another).
 *
 * A new tree when T_d is full evicts the stored tree farthest from the MAV (counted in evicted), except the
 * trees a detection of the same frame refers to (protected); when all are, the new tree is not stored
 * (counted in unstored). A full
 * visited list forgets its entry farthest from the MAV (counted in visited_forgotten). Association is
 * nearest-neighbour with exclusivity per frame: each detection goes to the nearest stored or visited tree
 * within the merge radius, no two detections of one frame to the same tree. It is done greedily on the
 * smallest (distance, detection, candidate order) pair left, which picks the same pairs as sorting all
 * of them (tree_memory.py) without a pair array (no RAM to spare on the Bolt).
 */
#include <math.h>
#include <string.h>

#include "nav_core.h"

void navTreesInit(NavTreeMemory* memory, int32_t capacity, int32_t visited_capacity) {
  memset(memory, 0, sizeof(*memory));
  memory->capacity = capacity;
  memory->visited_capacity = visited_capacity;
  memory->next_id = 1;
}

static int32_t clampCapacity(int32_t value, int32_t limit) {
  return value < 1 ? 1 : (value > limit ? limit : value);
}

NavTree* navTreesGet(NavTreeMemory* memory, int32_t id) {
  for (int32_t i = 0; i < memory->num_trees; i++) {
    if (memory->trees[i].id == id) {
      return &memory->trees[i];
    }
  }
  return NULL;
}

/* Candidate order k: stored trees first (insertion order), then the visited list (oldest first). */
static void candidatePosition(const NavTreeMemory* memory, int32_t k, double* x, double* y) {
  if (k < memory->num_trees) {
    *x = memory->trees[k].x;
    *y = memory->trees[k].y;
  } else {
    *x = memory->visited[k - memory->num_trees].x;
    *y = memory->visited[k - memory->num_trees].y;
  }
}

void navTreesAssociate(const NavTreeMemory* memory, const double (*points)[2], int32_t count,
                       double merge_radius, NavAssociation* result) {
  bool taken[NAV_MAX_TREES + NAV_MAX_VISITED];
  const int32_t candidates = memory->num_trees + memory->num_visited;
  memset(taken, 0, sizeof(taken));
  for (int32_t i = 0; i < count; i++) {
    result[i].kind = 0;
    result[i].id = 0;
  }
  for (;;) {
    int32_t best_i = -1, best_k = -1;
    double best_d = 0.0;
    for (int32_t i = 0; i < count; i++) {
      if (result[i].kind != 0) {
        continue;
      }
      for (int32_t k = 0; k < candidates; k++) {
        if (taken[k]) {
          continue;
        }
        double cx, cy;
        candidatePosition(memory, k, &cx, &cy);
        const double d = hypot(points[i][0] - cx, points[i][1] - cy);
        /* (d, i) order, ties kept in candidate order: strictly smaller wins */
        if (d <= merge_radius && (best_i < 0 || d < best_d || (d == best_d && i < best_i))) {
          best_i = i;
          best_k = k;
          best_d = d;
        }
      }
    }
    if (best_i < 0) {
      return;
    }
    taken[best_k] = true;
    if (best_k < memory->num_trees) {
      result[best_i].kind = 1;
      result[best_i].id = memory->trees[best_k].id;
    } else {
      result[best_i].kind = 2;
      result[best_i].id = memory->visited[best_k - memory->num_trees].id;
    }
  }
}

/* Index of the entry farthest from the MAV; ties go to the smaller id (tree_memory._farthest). */
static int32_t farthestTree(const NavTreeMemory* memory, double mx, double my) {
  int32_t best = 0;
  double best_d = hypot(memory->trees[0].x - mx, memory->trees[0].y - my);
  for (int32_t i = 1; i < memory->num_trees; i++) {
    const double d = hypot(memory->trees[i].x - mx, memory->trees[i].y - my);
    if (d > best_d || (d == best_d && memory->trees[i].id < memory->trees[best].id)) {
      best = i;
      best_d = d;
    }
  }
  return best;
}

static int32_t farthestVisited(const NavTreeMemory* memory, double mx, double my) {
  int32_t best = 0;
  double best_d = hypot(memory->visited[0].x - mx, memory->visited[0].y - my);
  for (int32_t i = 1; i < memory->num_visited; i++) {
    const double d = hypot(memory->visited[i].x - mx, memory->visited[i].y - my);
    if (d > best_d || (d == best_d && memory->visited[i].id < memory->visited[best].id)) {
      best = i;
      best_d = d;
    }
  }
  return best;
}

static void removeTreeAt(NavTreeMemory* memory, int32_t index) {
  memmove(&memory->trees[index], &memory->trees[index + 1],
          (size_t)(memory->num_trees - index - 1) * sizeof(NavTree));
  memory->num_trees--;
}

static bool isProtected(int32_t id, const int32_t* protected_ids, int32_t num_protected) {
  for (int32_t k = 0; k < num_protected; k++) {
    if (protected_ids[k] == id) {
      return true;
    }
  }
  return false;
}

/* Index of the unprotected tree farthest from the MAV (ties: smaller id), -1 if every tree is protected. */
static int32_t farthestUnprotected(const NavTreeMemory* memory, double mx, double my, const int32_t* protected_ids,
                                   int32_t num_protected) {
  int32_t best = -1;
  double best_d = 0.0;
  for (int32_t i = 0; i < memory->num_trees; i++) {
    if (isProtected(memory->trees[i].id, protected_ids, num_protected)) {
      continue;
    }
    const double d = hypot(memory->trees[i].x - mx, memory->trees[i].y - my);
    if (best < 0 || d > best_d || (d == best_d && memory->trees[i].id < memory->trees[best].id)) {
      best = i;
      best_d = d;
    }
  }
  return best;
}

int32_t navTreesAdd(NavTreeMemory* memory, double x, double y, int32_t t_ms, double u, double v,
                    double mav_x, double mav_y, const int32_t* protected_ids, int32_t num_protected,
                    int32_t* evicted, int32_t* num_evicted) {
  const int32_t capacity = clampCapacity(memory->capacity, NAV_MAX_TREES);
  *num_evicted = 0;
  while (memory->num_trees >= capacity) {
    const int32_t index = farthestUnprotected(memory, mav_x, mav_y, protected_ids, num_protected);
    if (index < 0) {
      memory->unstored++;
      return 0;
    }
    evicted[(*num_evicted)++] = memory->trees[index].id;
    removeTreeAt(memory, index);
    memory->evicted++;
  }
  NavTree* tree = &memory->trees[memory->num_trees++];
  tree->id = memory->next_id++;
  tree->x = x;
  tree->y = y;
  tree->hits = 1;
  tree->first_ms = t_ms;
  tree->last_ms = t_ms;
  tree->u = u;
  tree->v = v;
  return tree->id;
}

int32_t navTreesEvictToCapacity(NavTreeMemory* memory, double mav_x, double mav_y, int32_t* evicted) {
  const int32_t capacity = clampCapacity(memory->capacity, NAV_MAX_TREES);
  int32_t n = 0;
  while (memory->num_trees > capacity) {
    const int32_t index = farthestTree(memory, mav_x, mav_y);
    evicted[n++] = memory->trees[index].id;
    removeTreeAt(memory, index);
    memory->evicted++;
  }
  return n;
}

NavTree* navTreesRestore(NavTreeMemory* memory, int32_t id, int32_t hits, double u, double v, double mav_x,
                         double mav_y, int32_t* evicted, int32_t* num_evicted) {
  *num_evicted = 0;
  int32_t k = 0;
  while (k < memory->num_visited && memory->visited[k].id != id) {
    k++;
  }
  if (k == memory->num_visited) {
    return NULL;
  }
  const NavVisited entry = memory->visited[k];
  memmove(&memory->visited[k], &memory->visited[k + 1], (size_t)(memory->num_visited - k - 1) * sizeof(NavVisited));
  memory->num_visited--;
  const int32_t capacity = clampCapacity(memory->capacity, NAV_MAX_TREES);
  while (memory->num_trees >= capacity) {
    const int32_t index = farthestTree(memory, mav_x, mav_y);
    evicted[(*num_evicted)++] = memory->trees[index].id;
    removeTreeAt(memory, index);
    memory->evicted++;
  }
  NavTree* tree = &memory->trees[memory->num_trees++];
  tree->id = entry.id;
  tree->x = entry.x;
  tree->y = entry.y;
  tree->hits = hits;
  tree->first_ms = entry.t_ms;
  tree->last_ms = entry.t_ms;
  tree->u = u;
  tree->v = v;
  return tree;
}

void navTreesUpdate(NavTreeMemory* memory, int32_t id, double x, double y, int32_t t_ms, double u, double v) {
  NavTree* t = navTreesGet(memory, id);
  if (t == NULL) {
    return;
  }
  t->hits++;
  const double weight = 1.0 / (double)(t->hits < NAV_POSITION_AVERAGE_WINDOW ? t->hits
                                                                              : NAV_POSITION_AVERAGE_WINDOW);
  t->x += weight * (x - t->x);
  t->y += weight * (y - t->y);
  t->last_ms = t_ms;
  t->u = u;
  t->v = v;
}

bool navTreesMarkVisited(NavTreeMemory* memory, int32_t id, int32_t t_ms, double mav_x, double mav_y,
                         bool reached, bool revisit) {
  NavTree* t = navTreesGet(memory, id);
  if (t == NULL) {
    return false;
  }
  const NavTree tree = *t;
  removeTreeAt(memory, (int32_t)(t - memory->trees));
  const int32_t capacity = clampCapacity(memory->visited_capacity, NAV_MAX_VISITED);
  while (memory->num_visited >= capacity) {
    const int32_t index = farthestVisited(memory, mav_x, mav_y);
    memmove(&memory->visited[index], &memory->visited[index + 1],
            (size_t)(memory->num_visited - index - 1) * sizeof(NavVisited));
    memory->num_visited--;
    memory->visited_forgotten++;
  }
  NavVisited* entry = &memory->visited[memory->num_visited++];
  entry->id = tree.id;
  entry->x = tree.x;
  entry->y = tree.y;
  entry->t_ms = t_ms;
  entry->reached = reached;
  entry->revisit = revisit;
  return true;
}
