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
 * of them (tree_memory.py) without a pair array (no RAM to spare on the Bolt). A stored tree within
 * app.dupRadius of a reached tree is that tree seen again: dropped (counted in absorbed) into the visited list,
 * not reached, at the reached tree's position, so that a second detection of it is not stored again.
 */
#include <math.h>
#include <string.h>

#include "nav_internal.h"

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

/* The entry at index of T_d (visited false) or of the visited list: returns its id, its position in x, y. */
int32_t navTreesEntry(const NavTreeMemory* memory, bool visited, int32_t index, double* x, double* y) {
  if (visited) {
    *x = memory->visited[index].x;
    *y = memory->visited[index].y;
    return memory->visited[index].id;
  }
  *x = memory->trees[index].x;
  *y = memory->trees[index].y;
  return memory->trees[index].id;
}

/* Candidate order k: stored trees first (insertion order), then the visited list (oldest first). */
static void candidatePosition(const NavTreeMemory* memory, int32_t k, double* x, double* y) {
  const bool visited = k >= memory->num_trees;
  navTreesEntry(memory, visited, visited ? k - memory->num_trees : k, x, y);
}

void navTreesAssociate(const NavTreeMemory* memory, const double (*points)[2], const double* radii,
                       int32_t count, NavAssociation* result) {
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
        if (d <= radii[i] && (best_i < 0 || d < best_d || (d == best_d && i < best_i))) {
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

static void removeTreeAt(NavTreeMemory* memory, int32_t index) {
  memmove(&memory->trees[index], &memory->trees[index + 1],
          (size_t)(memory->num_trees - index - 1) * sizeof(NavTree));
  memory->num_trees--;
}

static void removeVisitedAt(NavTreeMemory* memory, int32_t index) {
  memmove(&memory->visited[index], &memory->visited[index + 1],
          (size_t)(memory->num_visited - index - 1) * sizeof(NavVisited));
  memory->num_visited--;
}

static bool isProtected(int32_t id, const int32_t* protected_ids, int32_t num_protected) {
  for (int32_t k = 0; k < num_protected; k++) {
    if (protected_ids[k] == id) {
      return true;
    }
  }
  return false;
}

/* Index of the entry of T_d (visited false) or of the visited list farthest from the MAV, but for the protected
 * ids; ties go to the smaller id (tree_memory._farthest). -1 if every entry is protected. */
static int32_t farthestEntry(const NavTreeMemory* memory, bool visited, double mx, double my,
                             const int32_t* protected_ids, int32_t num_protected) {
  const int32_t count = visited ? memory->num_visited : memory->num_trees;
  int32_t best = -1, best_id = 0;
  double best_d = 0.0;
  for (int32_t i = 0; i < count; i++) {
    double x, y;
    const int32_t id = navTreesEntry(memory, visited, i, &x, &y);
    if (isProtected(id, protected_ids, num_protected)) {
      continue;
    }
    const double d = hypot(x - mx, y - my);
    if (best < 0 || d > best_d || (d == best_d && id < best_id)) {
      best = i;
      best_id = id;
      best_d = d;
    }
  }
  return best;
}

/* Removes the stored tree at index, counted in evicted; returns its id. */
static int32_t evictAt(NavTreeMemory* memory, int32_t index) {
  const int32_t id = memory->trees[index].id;
  removeTreeAt(memory, index);
  memory->evicted++;
  return id;
}

/* Appends a tree to T_d (room made by the caller). */
static NavTree* storeTree(NavTreeMemory* memory, int32_t id, double x, double y, int32_t hits, int32_t t_ms, double u,
                          double v) {
  NavTree* tree = &memory->trees[memory->num_trees++];
  *tree = (NavTree){.id = id, .x = x, .y = y, .hits = hits, .first_ms = t_ms, .last_ms = t_ms, .u = u, .v = v};
  return tree;
}

int32_t navTreesAdd(NavTreeMemory* memory, double x, double y, int32_t t_ms, double u, double v,
                    double mav_x, double mav_y, const int32_t* protected_ids, int32_t num_protected,
                    int32_t* evicted, int32_t* num_evicted) {
  const int32_t capacity = clampCapacity(memory->capacity, NAV_MAX_TREES);
  *num_evicted = 0;
  while (memory->num_trees >= capacity) {
    const int32_t index = farthestEntry(memory, false, mav_x, mav_y, protected_ids, num_protected);
    if (index < 0) {
      memory->unstored++;
      return 0;
    }
    evicted[(*num_evicted)++] = evictAt(memory, index);
  }
  return storeTree(memory, memory->next_id++, x, y, 1, t_ms, u, v)->id;
}

int32_t navTreesEvictToCapacity(NavTreeMemory* memory, double mav_x, double mav_y, int32_t* evicted) {
  const int32_t capacity = clampCapacity(memory->capacity, NAV_MAX_TREES);
  int32_t n = 0;
  while (memory->num_trees > capacity) {
    evicted[n++] = evictAt(memory, farthestEntry(memory, false, mav_x, mav_y, NULL, 0));
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
  removeVisitedAt(memory, k);
  const int32_t capacity = clampCapacity(memory->capacity, NAV_MAX_TREES);
  while (memory->num_trees >= capacity) {
    evicted[(*num_evicted)++] = evictAt(memory, farthestEntry(memory, false, mav_x, mav_y, NULL, 0));
  }
  return storeTree(memory, entry.id, entry.x, entry.y, hits, entry.t_ms, u, v);
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

/* Appends a visited entry; a full list forgets its entry farthest from the MAV first (tree_memory._append_visited). */
static void appendVisited(NavTreeMemory* memory, int32_t id, double x, double y, int32_t t_ms, bool reached,
                          bool revisit, double mav_x, double mav_y) {
  const int32_t capacity = clampCapacity(memory->visited_capacity, NAV_MAX_VISITED);
  while (memory->num_visited >= capacity) {
    removeVisitedAt(memory, farthestEntry(memory, true, mav_x, mav_y, NULL, 0));
    memory->visited_forgotten++;
  }
  NavVisited* entry = &memory->visited[memory->num_visited++];
  *entry = (NavVisited){.id = id, .x = x, .y = y, .t_ms = t_ms, .reached = reached, .revisit = revisit};
}

bool navTreesMarkVisited(NavTreeMemory* memory, int32_t id, int32_t t_ms, double mav_x, double mav_y,
                         bool reached, bool revisit) {
  NavTree* t = navTreesGet(memory, id);
  if (t == NULL) {
    return false;
  }
  const NavTree tree = *t;
  removeTreeAt(memory, (int32_t)(t - memory->trees));
  appendVisited(memory, tree.id, tree.x, tree.y, t_ms, reached, revisit, mav_x, mav_y);
  return true;
}

/* Id of the first reached visited entry (oldest first), but for the one at skip, within radius of (x, y);
 * 0 if none. */
static int32_t reachedWithin(const NavTreeMemory* memory, double x, double y, double radius, int32_t skip) {
  for (int32_t k = 0; k < memory->num_visited; k++) {
    const NavVisited* e = &memory->visited[k];
    if (k != skip && e->reached && hypot(x - e->x, y - e->y) <= radius) {
      return e->id;
    }
  }
  return 0;
}

int32_t navTreesAbsorbReached(NavTreeMemory* memory, double radius, int32_t t_ms, double mav_x, double mav_y,
                              int32_t* dropped, int32_t* twins) {
  int32_t count = 0;
  int32_t i = 0;
  while (i < memory->num_trees) {
    const int32_t twin = reachedWithin(memory, memory->trees[i].x, memory->trees[i].y, radius, -1);
    if (twin == 0) {
      i++;
      continue;
    }
    double tx = 0.0, ty = 0.0;
    for (int32_t k = 0; k < memory->num_visited; k++) {
      if (memory->visited[k].id == twin) {
        tx = memory->visited[k].x;
        ty = memory->visited[k].y;
      }
    }
    dropped[count] = memory->trees[i].id;
    twins[count++] = twin;
    removeTreeAt(memory, i);
    memory->absorbed++;
    appendVisited(memory, dropped[count - 1], tx, ty, t_ms, false, false, mav_x, mav_y);
  }
  return count;
}

bool navTreesNearReached(const NavTreeMemory* memory, int32_t index, double radius) {
  return reachedWithin(memory, memory->visited[index].x, memory->visited[index].y, radius, index) != 0;
}
