// MuJoCo passive-force plugin "mantaray.kernel_contact": the object meets the sheet through a smooth kernel
// (sim/model/kernel_contact.py).
//
// Each step, each of the object's contact points below the sheet's kernel surface presses into it with a damped
// spring along the surface's normal and a stick spring along it capped by Coulomb; the damping is a ratio of critical
// for the reduced mass of the point's share of the object and the patch of sheet under it (the vertices' masses
// weighted by the kernel's squared weights: the same in kg on every mesh), so it does not act on the grams of sheet
// under the object with the damping an object's mass would want; the force acts on the object at the point and is
// shared back to the flex's vertices by the kernel's weights. The surface under (x, y) is the vertices' heights
// averaged with Wendland C2 weights w(r) = (1 - r/h)^4 (1 + 4 r/h) of support radius h [m]. The configuration (the
// names of the flex and the object's geom, h, the springs and the points) is written by sim/model/kernel_contact.py;
// the plugin's state is the kernel surface's height [m, world z] under the geom's centre at the last step (NaN off the
// sheet), which is how the Python side places an object on the surface without a second copy of it, then each point's
// stick stretch [m, world frame]: how far the point has moved along the sheet since it touched, the tangential spring's
// extension (Chrono's and Bullet's penalty friction), capped so the spring never pulls harder than mu N. So an object
// that friction should hold is held at any step, where a friction regularised by a slip speed lets it creep.

#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <mujoco/mujoco.h>

static const char* const kAttributes[] = {"flex",          "geom",     "width_m",  "stiffness_n_per_m", "share",
                                          "damping_ratio", "friction", "radius_m", "points_m"};
enum { kFlex, kGeom, kWidth, kStiffness, kShare, kDamping, kFriction, kRadius, kPoints, kAttributeCount };

typedef struct {
  int geom, body;                      // the object
  int first, count;                    // the flex's vertices in flexvert_xpos
  int* dof;                            // [count] each vertex's first of its x, y, z slides, or -1 with none
  mjtNum* mass;                        // [count] each vertex's mass [kg] (its body's)
  mjtNum h, k, zeta, mu, radius, top;  // [m], [N/m] a point's spring, [-] of critical, [-], [m], [m] the flex's radius
  mjtNum point_inverse_mass;           // [1/kg] of the point's share of the object
  int npoint;
  mjtNum* point;    // [3 npoint] the contact points in the geom's frame [m]
  mjtNum* weight;   // [count] scratch: each vertex's kernel weight under the point at hand
  mjtNum* stretch;  // [3 npoint] each point's stick stretch [m] after this step's compute, state from advance
} Kernel;

#define STATE_STRETCH 1  // the first stick stretch in the instance's state, after the surface height

static int read_number(const mjModel* m, int instance, int attribute, mjtNum* out) {
  const char* text = mj_getPluginConfig(m, instance, kAttributes[attribute]);
  char* end = NULL;
  if (!text || !*text) {
    mju_warning("mantaray.kernel_contact: config %s is missing", kAttributes[attribute]);
    return -1;
  }
  *out = strtod(text, &end);
  if (*end != '\0' || !isfinite(*out)) {
    mju_warning("mantaray.kernel_contact: config %s is not a number: '%s'", kAttributes[attribute], text);
    return -1;
  }
  return 0;
}

static int read_id(const mjModel* m, int instance, int attribute, mjtObj type) {
  const char* name = mj_getPluginConfig(m, instance, kAttributes[attribute]);
  int id = name ? mj_name2id(m, type, name) : -1;
  if (id < 0) mju_warning("mantaray.kernel_contact: config %s names nothing: '%s'", kAttributes[attribute], name);
  return id;
}

static void destroy(mjData* d, int instance) {
  Kernel* kernel = (Kernel*)d->plugin_data[instance];
  if (kernel) {
    free(kernel->dof);
    free(kernel->mass);
    free(kernel->point);
    free(kernel->weight);
    free(kernel->stretch);
    free(kernel);
  }
  d->plugin_data[instance] = 0;
}

// The numbers of points_m as strtod reads them one after another, written to out unless it is NULL: their count, or
// -1 where anything but blanks follows them. init and nstate both count with it, so the state fits the points.
static int read_points(const char* text, mjtNum* out) {
  int n = 0;
  char* end = NULL;
  for (const char* at = text; at && *at;) {
    mjtNum value = strtod(at, &end);
    if (end == at) break;
    if (out) out[n] = value;
    n++;
    at = end;
  }
  while (end && isspace((unsigned char)*end)) end++;
  return end && *end != '\0' ? -1 : n;
}

static int init(const mjModel* m, mjData* d, int instance) {
  Kernel* kernel = (Kernel*)calloc(1, sizeof(Kernel));
  d->plugin_data[instance] = (uintptr_t)kernel;
  if (!kernel) return -1;
  int flex = read_id(m, instance, kFlex, mjOBJ_FLEX);
  kernel->geom = read_id(m, instance, kGeom, mjOBJ_GEOM);
  mjtNum share = 0;
  if (flex < 0 || kernel->geom < 0 || read_number(m, instance, kWidth, &kernel->h) ||
      read_number(m, instance, kStiffness, &kernel->k) || read_number(m, instance, kShare, &share) ||
      read_number(m, instance, kDamping, &kernel->zeta) || read_number(m, instance, kFriction, &kernel->mu) ||
      read_number(m, instance, kRadius, &kernel->radius)) {
    destroy(d, instance);
    return -1;
  }
  if (kernel->h <= 0 || kernel->k <= 0 || share <= 0 || share > 1 || kernel->zeta < 0 || kernel->mu < 0 ||
      kernel->radius < 0) {
    mju_warning(
        "mantaray.kernel_contact: width and stiffness must be > 0, share in (0, 1], damping ratio, friction "
        "and radius >= 0");
    destroy(d, instance);
    return -1;
  }
  kernel->body = m->geom_bodyid[kernel->geom];
  kernel->k *= share;
  kernel->point_inverse_mass = 1 / (m->body_mass[kernel->body] * share);
  kernel->first = m->flex_vertadr[flex];
  kernel->count = m->flex_vertnum[flex];
  kernel->top = m->flex_radius[flex];
  kernel->dof = (int*)malloc(sizeof(int) * (size_t)kernel->count);
  kernel->mass = (mjtNum*)malloc(sizeof(mjtNum) * (size_t)kernel->count);
  kernel->weight = (mjtNum*)malloc(sizeof(mjtNum) * (size_t)kernel->count);
  const char* text = mj_getPluginConfig(m, instance, kAttributes[kPoints]);
  size_t length = text ? strlen(text) : 0;
  kernel->point = (mjtNum*)malloc(sizeof(mjtNum) * (length / 2 + 3));  // a number takes two characters at least
  if (!kernel->dof || !kernel->mass || !kernel->weight || !kernel->point) {
    destroy(d, instance);
    return -1;
  }
  for (int i = 0; i < kernel->count; i++) {
    int body = m->flex_vertbodyid[kernel->first + i];
    kernel->dof[i] = m->body_dofnum[body] == 3 ? m->body_dofadr[body] : -1;
    kernel->mass[i] = m->body_mass[body];
  }
  int n = read_points(text, kernel->point);
  if (n <= 0 || n % 3 != 0) {
    mju_warning("mantaray.kernel_contact: config points_m must be x y z triples [m]");
    destroy(d, instance);
    return -1;
  }
  kernel->npoint = n / 3;
  kernel->stretch = (mjtNum*)calloc((size_t)n, sizeof(mjtNum));
  if (!kernel->stretch) {
    destroy(d, instance);
    return -1;
  }
  return 0;
}

// One height, then a stretch for each point init reads.
static int nstate(const mjModel* m, int instance) {
  int numbers = read_points(mj_getPluginConfig(m, instance, kAttributes[kPoints]), NULL);
  return STATE_STRETCH + (numbers > 0 ? numbers : 0);
}

static void reset(const mjModel* m, mjtNum* state, void* data, int instance) {
  state[0] = NAN;
  Kernel* kernel = (Kernel*)data;
  int count = nstate(m, instance) - STATE_STRETCH;
  for (int i = 0; i < count; i++) state[STATE_STRETCH + i] = 0;
  if (kernel) memset(kernel->stretch, 0, sizeof(mjtNum) * 3 * (size_t)kernel->npoint);
}

// The step is taken: the stretches compute found become the state the next step starts from.
static void advance(const mjModel* m, mjData* d, int instance) {
  Kernel* kernel = (Kernel*)d->plugin_data[instance];
  mju_copy(d->plugin_state + m->plugin_stateadr[instance] + STATE_STRETCH, kernel->stretch, 3 * kernel->npoint);
}

// The tangential force [N] of a point's stick spring, and its stretch after this step: the stretch it started with,
// turned into the tangent plane of normal n at its length, grown by the tangential velocity over the step, and cut
// back so the spring and its damping b never exceed the Coulomb limit [N].
static void stick(mjtNum force[3], mjtNum stretch[3], const mjtNum n[3], const mjtNum tangential[3], mjtNum k, mjtNum b,
                  mjtNum limit, mjtNum dt) {
  mjtNum length = mju_norm3(stretch);
  mju_addToScl3(stretch, n, -mju_dot3(stretch, n));
  mjtNum turned = mju_norm3(stretch);
  if (turned > 1e-12) mju_scl3(stretch, stretch, length / turned);
  mju_addToScl3(stretch, tangential, dt);
  mju_scl3(force, stretch, -k);
  mju_addToScl3(force, tangential, -b);
  mjtNum size = mju_norm3(force);
  if (size > limit) {
    mju_scl3(force, force, limit / size);  // size > limit >= 0
    mju_scl3(stretch, force, -1 / k);      // slipping: the spring alone holds the limit
  }
}

// The kernel surface under (x, y): its height [m] and gradient, each vertex's weight in kernel->weight; returns the
// weights' sum (0 off the sheet, where nothing is written but the weights).
static mjtNum surface(Kernel* kernel, const mjtNum* vertex, mjtNum x, mjtNum y, mjtNum* z, mjtNum gradient[2]) {
  mjtNum total = 0, height = 0, dw[2] = {0, 0}, dwz[2] = {0, 0};
  for (int i = 0; i < kernel->count; i++) {
    const mjtNum* p = vertex + 3 * i;
    mjtNum dx = p[0] - x, dy = p[1] - y, r = sqrt(dx * dx + dy * dy), q = r / kernel->h;
    if (q >= 1) {
      kernel->weight[i] = 0;
      continue;
    }
    mjtNum w = pow(1 - q, 4) * (1 + 4 * q);
    kernel->weight[i] = w;
    total += w;
    height += w * p[2];
    if (r > 1e-12) {  // d w / d(x, y) of the point = dw/dr * -(dx, dy) / r
      mjtNum slope = 20 * q * pow(1 - q, 3) / kernel->h / r;
      dw[0] += slope * dx;
      dw[1] += slope * dy;
      dwz[0] += slope * dx * p[2];
      dwz[1] += slope * dy * p[2];
    }
  }
  if (total <= 0) return 0;
  *z = height / total;
  gradient[0] = (dwz[0] - *z * dw[0]) / total;  // the quotient rule on sum(w z) / sum(w)
  gradient[1] = (dwz[1] - *z * dw[1]) / total;
  return total;
}

static void compute(const mjModel* m, mjData* d, int instance, int capability_bit) {
  (void)capability_bit;
  Kernel* kernel = (Kernel*)d->plugin_data[instance];
  const mjtNum* vertex = d->flexvert_xpos + 3 * kernel->first;
  const mjtNum* centre = d->geom_xpos + 3 * kernel->geom;
  const mjtNum* rotation = d->geom_xmat + 9 * kernel->geom;
  const mjtNum* started = d->plugin_state + m->plugin_stateadr[instance] + STATE_STRETCH;
  mjtNum top = -INFINITY, z = NAN, gradient[2];
  mju_zero(kernel->stretch, 3 * kernel->npoint);  // a point off the sheet lets go
  for (int i = 0; i < kernel->count; i++) top = fmax(top, vertex[3 * i + 2]);
  top += kernel->top;
  d->plugin_state[m->plugin_stateadr[instance]] =
      surface(kernel, vertex, centre[0], centre[1], &z, gradient) > 0 ? z : NAN;
  mjtNum velocity[6], force_sum[3] = {0, 0, 0}, torque_sum[3] = {0, 0, 0};
  mj_objectVelocity(m, d, mjOBJ_GEOM, kernel->geom, velocity, 0);  // [rot, lin] in the world frame
  for (int j = 0; j < kernel->npoint; j++) {
    mjtNum world[3];
    mju_mulMatVec3(world, rotation, kernel->point + 3 * j);
    mju_addTo3(world, centre);
    if (world[2] - kernel->radius >= top) continue;
    mjtNum total = surface(kernel, vertex, world[0], world[1], &z, gradient);
    if (total <= 0) continue;
    mjtNum n[3] = {-gradient[0], -gradient[1], 1};
    mju_normalize3(n);
    mjtNum depth = kernel->radius + kernel->top - (world[2] - z) * n[2];
    if (depth <= 0) continue;
    mjtNum at[3], arm[3], spin[3], relative[3];
    mju_addScl3(at, world, n, -kernel->radius);  // where the point meets the sheet
    mju_sub3(arm, at, centre);
    mju_cross(spin, velocity, arm);
    mju_add3(relative, velocity + 3, spin);
    mjtNum sheet = 0;                          // [1/kg] the inverse mass of the patch of sheet under the point
    for (int i = 0; i < kernel->count; i++) {  // less the sheet's velocity under the point
      if (kernel->weight[i] > 0 && kernel->dof[i] >= 0) {
        mjtNum part = kernel->weight[i] / total;
        mju_addToScl3(relative, d->qvel + kernel->dof[i], -part);
        if (kernel->mass[i] > 0) sheet += part * part / kernel->mass[i];
      }
    }
    mjtNum v_n = mju_dot3(relative, n), tangential[3];
    mju_addScl3(tangential, relative, n, -v_n);
    mjtNum b = kernel->zeta * 2 * sqrt(kernel->k / (kernel->point_inverse_mass + sheet));  // [N s/m]
    mjtNum normal = fmax(0.0, kernel->k * depth - b * v_n);  // [N] a penalty spring cannot pull
    mjtNum force[3], torque[3], *stretch = kernel->stretch + 3 * j;
    mju_copy3(stretch, started + 3 * j);
    stick(force, stretch, n, tangential, kernel->k, b, kernel->mu * normal, m->opt.timestep);
    mju_addToScl3(force, n, normal);
    mju_cross(torque, arm, force);
    mju_addTo3(force_sum, force);
    mju_addTo3(torque_sum, torque);
    for (int i = 0; i < kernel->count; i++) {  // each vertex bears its share of the reaction
      if (kernel->weight[i] > 0 && kernel->dof[i] >= 0) {
        mju_addToScl3(d->qfrc_passive + kernel->dof[i], force, -kernel->weight[i] / total);
      }
    }
  }
  mj_applyFT(m, d, force_sum, torque_sum, centre, kernel->body, d->qfrc_passive);
}

mjPLUGIN_LIB_INIT(mantaray_kernel_contact) {
  mjpPlugin plugin;
  mjp_defaultPlugin(&plugin);
  plugin.name = "mantaray.kernel_contact";
  plugin.capabilityflags |= mjPLUGIN_PASSIVE;
  plugin.nattribute = kAttributeCount;
  plugin.attributes = kAttributes;
  plugin.nstate = nstate;
  plugin.init = init;
  plugin.destroy = destroy;
  plugin.reset = reset;
  plugin.advance = advance;
  plugin.compute = compute;
  mjp_registerPlugin(&plugin);
}
