/* Chladni's C API, version 2: the modal-sound runtime for engines. Handles are small structs
 * passed by value (chladni_bank, chladni_object, chladni_shaker; id 0 is none) and the runtime
 * pointer; calls return a status, with chladni_last_error() for the message; no exception crosses
 * it. Names follow chladni_<noun>_<verb>.
 *
 * Threads. Three roles, each on one thread at a time (control and game may be the same thread):
 *  - control: chladni_runtime_create/destroy, the chladni_bank_* calls, chladni_object_spawn,
 *    chladni_object_remove, chladni_shaker_add, chladni_shaker_remove, chladni_contact_add,
 *    chladni_contact_remove and the chladni_paper_* calls. These allocate and (but create/destroy)
 * may run while the audio thread renders: a new object or shaker is made here and handed to the
 * audio thread through a queue, placed at the next block boundary; a removed one fades out there
 * and is freed here afterwards.
 *  - game: chladni_impact_post, chladni_object_move, chladni_listener_set,
 *    chladni_shaker_shake and chladni_contact_post. Lock-free and allocation-free; they reach
 *    the audio thread through a single-producer single-consumer queue.
 *  - audio: chladni_runtime_render. It never allocates, locks or waits (beyond the filterbank's
 *    own work, and, on a Vulkan queue shared with the application, its lock_queue once a block).
 *  chladni_runtime_time, chladni_runtime_latency and chladni_last_error may be called anywhere.
 *
 * Lifetimes. The runtime owns every bank and object. chladni_bank_release gives up the caller's
 * bank: it is freed once no object of it is left (removed objects count until their fade ends).
 * chladni_runtime_destroy frees everything. A handle of something removed or released is refused
 * with CHLADNI_INPUT_ERROR, never reused by another (ids carry a generation).
 *
 * Time: the runtime's clock is the audio it has rendered (chladni_runtime_time). A posted command
 * carries a time on that clock; impacts land on their sample (sub-sample accurate), moves and
 * listener changes on their first sample, the gains then ramping over gain_ramp samples. A
 * command whose time has passed applies at once; one more than config.horizon seconds ahead is
 * refused. See docs/embedding.md, which also lists what changed from version 1. */
#ifndef CHLADNI_H
#define CHLADNI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CHLADNI_API_VERSION 2

typedef enum chladni_status {
  CHLADNI_OK = 0,
  CHLADNI_INPUT_ERROR = 2,   /* a bad argument or file; chladni_last_error() names it */
  CHLADNI_QUEUE_FULL = 3,    /* no room for the command until the next render */
  CHLADNI_NO_DEVICE = 4,     /* backend GPU without a usable Vulkan device */
  CHLADNI_INTERNAL_ERROR = 5 /* a bug: please report chladni_last_error() */
} chladni_status;

typedef enum chladni_backend {
  CHLADNI_BACKEND_CPU = 0,
  CHLADNI_BACKEND_GPU = 1,
  CHLADNI_BACKEND_AUTO = 2 /* the GPU when a Vulkan device is usable, else the CPU */
} chladni_backend;

/* A Vulkan device the application made (its renderer's), for the GPU backend to share: the
 * runtime then creates no instance or device of its own and records on the queue it is given.
 * The handles are the application's VkInstance, VkPhysicalDevice and VkDevice (dispatchable
 * handles, passed as pointers), made through the system Vulkan loader, which the runtime calls;
 * they must outlive the runtime, which destroys only what it made on them. The queue's family
 * must support compute. Give the runtime a queue of its own where the device has one: then the
 * two sides need no synchronisation beyond what each does with its own work. Where the queue
 * is shared with the application's threads (a device with one queue), lock_queue and
 * unlock_queue are called around each of the runtime's submits: from chladni_runtime_render,
 * once per block, so the application should hold that lock only briefly. */
typedef struct chladni_vulkan_device {
  void* instance;
  void* physical_device;
  void* device;
  uint32_t queue_family;
  uint32_t queue_index;
  void* get_instance_proc_addr;   /* optional: the loader's PFN_vkGetInstanceProcAddr, checked */
  void (*lock_queue)(void* user); /* both or neither */
  void (*unlock_queue)(void* user);
  void* user;
} chladni_vulkan_device;

typedef struct chladni_config {
  chladni_backend backend; /* CPU */
  double sample_rate;      /* 48000 */
  uint32_t block_size;     /* 256: frames per filterbank call (renders split larger requests) */
  int channels;            /* 2: 1 or 2 (constant-power pan) */
  uint32_t mode_budget;    /* 65536: modes resident at once; the least audible are stolen */
  uint32_t max_objects;    /* 256: objects alive or fading out at once */
  uint32_t queue_capacity; /* 4096: commands posted between two renders */
  uint32_t gain_ramp;      /* 256: samples over which gain changes ramp, across renders */
  int threads;             /* 0: all hardware threads (CPU backend) */
  uint32_t shaker_slots;   /* 4096: resonances of all shakers together (0: no shakers) */
  uint32_t max_shakers;    /* 64 */
  int gpu_pipeline;        /* 1: the GPU backend's render returns without waiting for the
                              device, its output block_size frames late
                              (chladni_runtime_latency); 0: each render waits for its own block */
  double horizon;          /* 60: seconds ahead of the clock a command may be timed */
  const chladni_vulkan_device* vulkan; /* NULL: the GPU backend opens a device of its own; else
                                          GPU and AUTO run on this one (copied at creation) */
  uint32_t max_papers;                 /* 4: paper sheets alive or ringing out at once (0: none) */
  uint32_t contact_slots; /* 0 (none): modes of all continuous contacts together (each contact
                             takes its bodies' modes). The filterbank runs every slot below the
                             highest in use, so these cost each block, used or not (as
                             shaker_slots do): ask for what the game needs */
  uint32_t max_contacts;  /* 64: contacts alive or ringing down at once */
} chladni_config;

typedef struct chladni_runtime chladni_runtime;
typedef struct chladni_bank {
  uint64_t id;
} chladni_bank;
typedef struct chladni_object {
  uint64_t id;
} chladni_object;
typedef struct chladni_shaker {
  uint64_t id;
} chladni_shaker;
typedef struct chladni_paper {
  uint64_t id;
} chladni_paper;
typedef struct chladni_contact {
  uint64_t id;
} chladni_contact;

/* Fills `config` with the defaults above. */
void chladni_config_default(chladni_config* config);
/* The calling thread's last error message ("" when none). Valid until its next failing call. */
const char* chladni_last_error(void);

chladni_status chladni_runtime_create(const chladni_config* config, chladni_runtime** out);
void chladni_runtime_destroy(chladni_runtime* runtime);
/* The filterbank in words, e.g. "cpu (avx512, 2 threads)". */
const char* chladni_runtime_backend(const chladni_runtime* runtime);

/* Banks (control calls): a soundbank (chladni precompute) from a file or from its bytes, or
 * inline modes (frequency Hz below Nyquist, decay 1/s, pressure at 1 m per N s within 1e6 Pa).
 * A soundbank's modes above the runtime's Nyquist frequency are dropped; a bank with none left
 * is refused. */
chladni_status chladni_bank_load_file(chladni_runtime* runtime, const char* path,
                                      chladni_bank* out);
chladni_status chladni_bank_load_memory(chladni_runtime* runtime, const void* bytes, size_t size,
                                        chladni_bank* out);
chladni_status chladni_bank_from_modes(chladni_runtime* runtime, const double* frequency_hz,
                                       const double* decay, const double* amplitude, size_t count,
                                       chladni_bank* out);
/* A free-free rectangular bar described analytically (Euler-Bernoulli bending across its
 * thickness and width, axial modes), as a scene's "bar" object: no precompute needed. The bar
 * lies along x from 0 to length, its top face at z = thickness. */
typedef struct chladni_bar {
  double length, width, thickness; /* m (x, y, z) */
  double youngs_modulus;           /* Pa */
  double poisson_ratio;
  double density;       /* kg/m^3 */
  double rayleigh[2];   /* damping c = rayleigh[0] + rayleigh[1] omega^2 (1/s, s) */
  double max_frequency; /* Hz: modes above are dropped (and those above Nyquist) */
} chladni_bar;
/* Fills `bar` with the scene format's defaults: a 0.3 x 0.03 x 0.01 m steel bar. */
void chladni_bar_default(chladni_bar* bar);
chladni_status chladni_bank_from_bar(chladni_runtime* runtime, const chladni_bar* bar,
                                     chladni_bank* out);
/* Gives up the caller's bank: it is freed when its last object has faded out. Control call. */
chladni_status chladni_bank_release(chladni_runtime* runtime, chladni_bank bank);
/* Modes and surface points (0: inline modes) of a bank; 0 for an unknown handle. Control. */
size_t chladni_bank_mode_count(const chladni_runtime* runtime, chladni_bank bank);
size_t chladni_bank_point_count(const chladni_runtime* runtime, chladni_bank bank);
/* The axis-aligned box of a bank's surface points in its own frame (m), for a collision shape.
 * CHLADNI_INPUT_ERROR for a bank without geometry (inline modes). Control call. */
chladni_status chladni_bank_bounds(const chladni_runtime* runtime, chladni_bank bank, double min[3],
                                   double max[3]);
/* The solid's mass (kg): its closed surface's volume times the material's density, for a
 * rigid body. 0 for inline modes or an unknown handle. Control call. */
double chladni_bank_mass(const chladni_runtime* runtime, chladni_bank bank);

/* An instance of a bank at a pose (position in m, each coordinate within 1e9; orientation a
 * unit quaternion w, x, y, z, object frame to world) with a gain in [0, 1e6]. It sounds from the
 * next block the audio thread starts; commands may be posted for it at once. CHLADNI_QUEUE_FULL
 * when max_objects objects are alive or still fading out. Control call. */
chladni_status chladni_object_spawn(chladni_runtime* runtime, chladni_bank bank,
                                    const double position[3], const double orientation[4],
                                    double gain, chladni_object* object);
/* Silences an object (its sound fades out over gain_ramp samples, and its place is reused after
 * that) and refuses commands for it from now on. Control call. */
chladni_status chladni_object_remove(chladni_runtime* runtime, chladni_object object);

typedef struct chladni_impact {
  chladni_object object;
  double time;         /* s on the runtime's clock */
  double impulse;      /* N s, in (0, 1e6] */
  double direction[3]; /* object frame; normalized here */
  double point[3];     /* object frame: the nearest surface point is struck ... */
  int64_t vertex;      /* ... unless this is >= 0: that surface point */
  double contact_time; /* s, 0 to 0.1: a half-sine force; 0 is an ideal impulse */
} chladni_impact;

/* Commands: game thread; CHLADNI_QUEUE_FULL when the queue has no room until the next render. */
chladni_status chladni_impact_post(chladni_runtime* runtime, const chladni_impact* impact);
chladni_status chladni_object_move(chladni_runtime* runtime, chladni_object object, double time,
                                   const double position[3], const double orientation[4]);
chladni_status chladni_listener_set(chladni_runtime* runtime, double time, const double position[3],
                                    const double forward[3], const double up[3]);

/* A shaker: PhISEM particles (Cook 1997) in or at an object, played by chladni_shaker_shake. */
typedef struct chladni_shaker_desc {
  chladni_object object;  /* the object the particles are in */
  const char* instrument; /* a PhISEM preset: "maraca", "gravel", "coins", ... (chladni shake
                             --list) */
  double particles;       /* 0: the instrument's own count */
  int resonate_object;    /* 1: the particles strike the object's surface and ring its modes;
                             0: the instrument's own resonances, sounding at the object */
  double impulse;         /* N s per unit of excitation on the surface (resonate_object); 0: 1e-3 */
} chladni_shaker_desc;

/* Adds a shaker, silent until shaken, from the next block. Its sound follows its object's pose;
 * it fades out and is freed when removed or when its object is. CHLADNI_QUEUE_FULL when
 * max_shakers shakers are alive or fading out. Control call. */
chladni_status chladni_shaker_add(chladni_runtime* runtime, const chladni_shaker_desc* desc,
                                  chladni_shaker* shaker);
/* Fades a shaker out over gain_ramp samples and frees it; its shakes are refused from now on.
 * Control call. */
chladni_status chladni_shaker_remove(chladni_runtime* runtime, chladni_shaker shaker);
/* Shakes: adds `energy` (0 to 1] to the particles at `time`. Game thread, as the other
 * commands. */
chladni_status chladni_shaker_shake(chladni_runtime* runtime, chladni_shaker shaker, double time,
                                    double energy);

/* A continuous contact (docs/contact.md): something sliding or rolling on an object, or two
 * objects rubbing, whose normal force, speeds and points the game posts once per physics step.
 * The object's modes (and the other's, pressed the other way) ring from a surface profile read
 * at the slip speed or seen through a rolling patch. */
typedef struct chladni_contact_desc {
  chladni_object object; /* the body whose modes it drives (a bank with surface points, or
                            inline modes) */
  chladni_object other;  /* id 0: none; else a second body, driven with the opposite force */
  const char* surface;   /* a surface preset: "steel", "aluminium", "glass", "ceramic", "wood",
                            "stone", "plastic"; NULL: "steel" */
  double level;          /* sliding force fluctuation per newton of normal force; 0: the
                            surface's own */
  uint64_t seed;         /* 0: 1 */
  double ribs;           /* a ribbed texture's spacing (m, up to 0.1); 0: none */
  double rib_depth;      /* its rms beside the surface's own roughness (0 to 100) */
} chladni_contact_desc;
typedef struct chladni_contact_state {
  double time;           /* s on the runtime's clock at which these values hold */
  double point[3];       /* on the object, its frame: the nearest surface point is driven */
  double other_point[3]; /* on the other, its frame (ignored without one) */
  double normal_force;   /* N, [0, 1e6] */
  double slip_speed;     /* m/s, [0, 100] */
  double rolling_speed;  /* m/s, [0, 100] */
} chladni_contact_state;
/* Adds a contact, silent until its first state, from the next block. CHLADNI_QUEUE_FULL when
 * max_contacts contacts are alive or ringing down. Control call: the surface's tables are made
 * here (about 2 MB). */
chladni_status chladni_contact_add(chladni_runtime* runtime, const chladni_contact_desc* desc,
                                   chladni_contact* contact);
/* The contact's state at `state->time`, typically once per physics step: between two posts the
 * runtime interpolates every value per sample, so post each step's state at the time the step
 * ends (a step behind the game's clock is smooth; a state posted for a time already rendered
 * holds from now). The force fades in over gain_ramp samples from the first post. A point
 * farther from the object's box than a tenth of its size, a non-finite value, or one out of
 * range is refused (CHLADNI_INPUT_ERROR); so is a state earlier than the last one posted. Game
 * thread. */
chladni_status chladni_contact_post(chladni_runtime* runtime, chladni_contact contact,
                                    const chladni_contact_state* state);
/* Ends a contact: its force fades out over gain_ramp samples, its modes ring down as after an
 * impact, and it is freed after. Ending an object ends its contacts. Control call. */
chladni_status chladni_contact_remove(chladni_runtime* runtime, chladni_contact contact);
/* Paper sound (Schreck et al. 2016; docs/paper.md): a sheet whose vertex positions the game posts
 * once per animation frame. Each frame is analysed for friction and crumpling as `chladni paper`
 * does, on the calling (control) thread, and its audio is handed to the audio thread, which mixes
 * it in one frame period after the sheet's first frame was posted (plus chladni_runtime_latency):
 * the same samples `chladni paper` renders from an animation of the same frames. */
typedef struct chladni_paper_plane {
  double point[3];     /* m */
  double normal[3];    /* unit, towards the paper's side */
  const char* surface; /* the friction recordings it rubs with; NULL: "wood" */
} chladni_paper_plane;

typedef struct chladni_paper_desc {
  /* The sheet: a paper animation's JSON (docs/paper-format.md), whose mesh, anchors, planes,
   * listener, frame rate and contact distance are taken (its frames are not played); or, when
   * NULL, the fields below. */
  const char* animation;
  uint32_t vertex_count;
  const uint32_t* triangles; /* 3 per triangle, vertex indices */
  uint32_t triangle_count;
  const chladni_paper_plane* planes; /* rigid planes it may touch (a table, a wall) */
  uint32_t plane_count;
  double frame_rate;       /* frames/s, one chladni_paper_post_frame each; 0: 60 */
  double contact_distance; /* m a vertex touches a plane within; 0: 0.002 */
  double listener[9];      /* position, forward, up (m); all 0: (0,-0.5,0.3), +y, +z */
  int follow_listener;     /* 1: heard from where chladni_listener_set last put the listener
                              (once it has been set), updated at each posted frame */
  /* How it sounds (all sheets). */
  const char* mode;     /* "database", "modal" or "both"; NULL: database when `database` is
                           given, else modal (the sheet's own modes, no recordings needed) */
  const char* database; /* a paper sound database folder (paper_db.json) at the runtime's rate */
  uint64_t seed;        /* 0: 1 */
  double gain;          /* 0: 1 */
} chladni_paper_desc;

/* Adds a paper sheet. CHLADNI_QUEUE_FULL when max_papers sheets are alive or ringing out.
 * Control call. */
chladni_status chladni_paper_add(chladni_runtime* runtime, const chladni_paper_desc* desc,
                                 chladni_paper* paper);
/* The sheet's next frame: `xyz` holds 3 floats (m) per vertex. `held` lists the vertices held
 * this frame (fingers, clamps), replacing the animation's anchors; NULL keeps them (none for an
 * inline sheet). Frames follow one another at desc.frame_rate: post one per animation frame.
 * CHLADNI_QUEUE_FULL, the frame not taken, when the audio thread has not yet played what the
 * earlier frames made (half a second or more is buffered): post it again after a render. Control
 * call: the analysis allocates. */
chladni_status chladni_paper_post_frame(chladni_runtime* runtime, chladni_paper paper,
                                        const float* xyz, uint32_t vertex_count,
                                        const uint32_t* held, uint32_t held_count);
/* Ends a sheet: its sounds ring out (half a second) and it is freed after. Control call. */
chladni_status chladni_paper_remove(chladni_runtime* runtime, chladni_paper paper);

/* Renders `frames` interleaved frames into `out` (frames * channels floats, Pa at the
 * listener). Audio thread: no allocation, no lock, no wait beyond the filterbank's own work. */
chladni_status chladni_runtime_render(chladni_runtime* runtime, float* out, uint32_t frames);
/* Seconds rendered so far, as of the last render to return; any thread may ask. */
double chladni_runtime_time(const chladni_runtime* runtime);
/* Seconds by which the output lags the runtime's clock: an event at time t is heard at output
 * time t + latency. 0 on the CPU backend; block_size / sample_rate on the pipelined GPU one. */
double chladni_runtime_latency(const chladni_runtime* runtime);

#ifdef __cplusplus
}
#endif

#endif /* CHLADNI_H */
