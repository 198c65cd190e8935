;;;; tangled/physics.lisp -- GENERATED from physics.org by 'make tangle'. Do not edit.

;; [[file:../physics.org::#NEZQ3X][The package:1]]
(defpackage #:luv-physics
  (:use #:cl)
  (:nicknames #:physics)
  (:documentation "Rigid spheres in a block world, written as the literate page physics.org. #NEZQ3X")
  (:export
   ;; Which wide instructions this machine offers (#JKM0PY), listed with the families (#R9M4PV)
   #:available-kernel-families
   ;; Types, the hot-loop policy and the parameters (#V0CAB5)
   #:*physics-contact-hertz* #:*physics-contact-damping-ratio* #:*physics-contact-push-max*
   #:*physics-load-stiffening* #:*physics-crowded-relax-passes* #:*physics-crowded-depth* #:*physics-linear-slop* #:*physics-speculative-margin* #:*physics-pair-skin* #:*physics-restitution-threshold*
   #:*physics-hit-speed* #:*physics-sleep-speed* #:*physics-time-to-sleep* #:*physics-wake-speed*
   #:*physics-brace-mass-ratio*
   #:*physics-reach-limit* #:*physics-max-speed* #:+physics-coordinate-limit+
   #:*physics-body-budget* #:*physics-terrain-chunk-budget*
   ;; Bad input is a condition that names the value (#C0ND1T)
   #:physics-error #:invalid-physics-number #:invalid-physics-radius #:invalid-physics-parameter
   #:stale-physics-handle #:physics-world-busy #:physics-world-invalid #:physics-budget-exceeded
   #:+physics-min-radius+ #:+physics-max-radius+ #:+physics-min-mass+ #:+physics-max-mass+ #:+physics-max-friction+
   #:+physics-max-gravity+ #:+physics-min-step-seconds+
   ;; Terrain (#H2W9DJ)
   #:voxel-terrain #:make-voxel-terrain #:terrain-solid-p #:terrain-resident-p #:fill-terrain
   ;; The world, kernel families, making worlds and bodies (#W0RLD7, #R9M4PV, #M4K3WD)
   #:physics-world #:physics-world-event-handler #:physics-world-step-count
   #:kernel-family #:scalar-kernels #:make-physics-world #:add-physics-body #:physics-body-in-solid-cell
   #:physics-body-alive-p #:physics-body-awake-p #:physics-body-position #:physics-body-velocity
   #:physics-body-angular-velocity #:physics-body-orientation #:physics-body-radius
   #:physics-world-awake-count #:physics-world-sleeping-count
   ;; Events, sleep, boxes (#E7V3NT, #QKS4GZ, #K1N3BX)
   #:map-physics-events #:remove-physics-body #:set-physics-body-velocity
   #:wake-physics-bodies-near #:post-physics-box
   ;; Categories and masks, sensors (#F1LT3R, #S3NS0R)
   #:set-physics-body-filter #:physics-body-filter
   #:add-physics-sensor #:remove-physics-sensor #:physics-sensor-bodies
   ;; The solver's entry points (#K3RNLS)
   #:physics-integrate-velocities #:physics-warm-start #:physics-solve-contacts
   #:physics-integrate-positions
   ;; The step, determinism, validation, bodies as objects (#IDVK7G, #S6T2MV, #V4L1D8, #B0DY0B)
   #:step-physics-world #:*physics-phases* #:physics-world-last-step-contact-count
   #:physics-world-last-step-held-out-count #:physics-world-last-step-buried-count
   #:physics-world-last-step-color-count #:physics-world-last-step-real-seconds
   #:physics-world-max-penetration #:physics-world-max-approach-speed #:physics-world-overflow-count
   #:physics-world-state-hash #:validate-physics-world
   #:physics-body #:physics-body-world #:physics-body-handle
   ;; Kernel families (#R9M4PV, #F4M1LY)
   #:register-kernel-family #:sse-kernels #:avx2-kernels
   ;; Kinds and springs (#JAU0EF), the player (#H7P4CX)
   #:*physics-body-kinds* #:add-physics-body-of-kind #:physics-body-kind #:physics-body-kind-name
   #:physics-spring #:make-physics-spring #:make-fountain #:make-lava-spring #:run-physics-springs
   #:physics-player #:make-physics-player #:step-physics-player #:advance-physics-player
   #:physics-player-x #:physics-player-y #:physics-player-z #:physics-player-vx #:physics-player-vy
   #:physics-player-vz #:physics-player-grounded #:physics-player-eye #:post-physics-player
   #:*physics-player-shape*
   ;; The step hook (#W0RLD7)
   #:physics-world-step-hook
   ;; Asking the world (#C4STRY, #R4YC57, #S9WEEP, #OV3RLP)
   #:physics-hit #:make-physics-hit #:physics-hit-kind #:physics-hit-handle #:physics-hit-owner
   #:physics-hit-cell-x #:physics-hit-cell-y #:physics-hit-cell-z #:physics-hit-x #:physics-hit-y
   #:physics-hit-z #:physics-hit-nx #:physics-hit-ny #:physics-hit-nz #:physics-hit-distance
   #:physics-ray-cast #:physics-sphere-cast
   #:map-physics-bodies-in-sphere #:map-physics-bodies-in-box
   #:map-physics-cells-in-sphere #:map-physics-cells-in-box
   ;; Giving back the room the buffers grew to (#QKS4GZ)
   #:trim-physics-world
   #:physics-world-bytes
   ;; Exported functions refuse a non-world by name (#C0ND1T, #M4K3WD)
   #:not-a-physics-world
   ;; A world as an object, and both in the inspector (#4YDMX5)
   #:install-swank-inspection
   ;; A world's handles (#K5DF9S)
   #:physics-world-handles
   ;; Features: a world pays only for what it uses (#FEAT5X)
   #:physics-world-features #:physics-feature-omitted #:set-physics-body-material
   ;; Acting on bodies: a new place, impulses and spin, forces and gravity scales (#T3LPRT, #1MPULS, #F0RC3S)
   #:set-physics-body-position #:apply-physics-impulse #:apply-physics-impulse-at
   #:set-physics-body-angular-velocity #:apply-physics-force #:physics-body-force
   #:set-physics-body-gravity-scale #:physics-body-gravity-scale
   #:+physics-max-acceleration+ #:+physics-max-gravity-scale+
   ;; Joints (#J0STOR)
   #:add-physics-joint #:remove-physics-joint #:physics-joint-alive-p #:physics-world-joint-count
   #:physics-joint-bodies #:physics-joint-length #:physics-joint-impulse
   #:physics-joint #:physics-joint-world #:physics-joint-handle #:physics-world-joint-objects
   ;; Boxes (#BXR0WS)
   #:add-physics-box #:physics-body-box-p #:physics-box-half-extents
   ;; A snapshot holds what decides the next step (#SN4P0T)
   #:snapshot-physics-world #:restore-physics-world #:write-physics-world #:read-physics-world
   #:physics-snapshot-invalid #:physics-snapshot-truncated
   #:physics-snapshot-wrong-magic #:physics-snapshot-wrong-version #:physics-snapshot-checksum-mismatch
   #:physics-snapshot-other-layout #:physics-snapshot-missing-features
   ;; Every core (#W0RKP1)
   #:close-physics-world #:physics-world-workers #:+physics-max-workers+))

(in-package #:luv-physics)
;; The package:1 ends here

;; [[file:../physics.org::#V0CAB5][Types, the hot-loop policy and the parameters:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +kernel-policy+ '(optimize (speed 3) (safety 0) (debug 0))
    "The policy of every hot loop: speed, no run-time checks; inputs are checked at the API. #V0CAB5"))

(deftype f32 ()
  "The float of every number the solver touches. #V0CAB5"
  'single-float)

(deftype f32-column ()
  "A column of single-floats. #V0CAB5"
  '(simple-array single-float (*)))

(deftype fixnum-column ()
  "A column of fixnums. #V0CAB5"
  '(simple-array fixnum (*)))

(deftype index ()
  "A row number or an array index. #V0CAB5"
  '(integer 0 #.(1- (ash 1 40))))

(declaim (inline f32))
(defun f32 (x)
  "X as a single-float. #V0CAB5"
  (coerce x 'single-float))

(declaim (inline fixnum-column-copy fixnum-room))
(defun fixnum-column-copy (column size keep)
  "A fresh fixnum column of SIZE entries: the first KEEP are COLUMN's, the rest 0. #V0CAB5"
  (declare (type fixnum-column column) (type index size keep))
  (replace (make-array size :element-type 'fixnum :initial-element 0) column :end2 keep))

(defun fixnum-room (column need &key (keep (length column)) (least 64))
  "COLUMN when it has room for NEED entries; else a fresh fixnum column of NEED entries, twice
COLUMN's length or LEAST, whichever is most, holding COLUMN's first KEEP entries. #V0CAB5"
  (declare (type fixnum-column column) (type index need keep least))
  (if (>= (length column) need)
      column
      (fixnum-column-copy column (max need (* 2 (length column)) least) keep)))

(defmacro block-ref (data base offset)
  "Float BASE+OFFSET of the f32-column DATA, OFFSET a constant folded into the load's address
(SBCL's internal, unchecked accessor; see [[#R0WS8T]]). #V0CAB5"
  `(sb-kernel:data-vector-ref-with-offset ,data (the index ,base) ,offset))

(defsetf block-ref (data base offset) (value)
  "Store VALUE as float BASE+OFFSET of DATA, the offset folded as in block-ref. #V0CAB5"
  `(progn (sb-kernel:data-vector-set-with-offset ,data (the index ,base) ,offset (the single-float ,value))
          ,value))

(defparameter *physics-contact-hertz* 30.0
  "Stiffness of a contact between two awake bodies, in Hz; static contacts get twice it. #V0CAB5")

(defparameter *physics-contact-damping-ratio* 10.0
  "Damping ratio of the soft contact spring (critically damped is 1). #V0CAB5")

(defparameter *physics-contact-push-max* 3.0
  "Fastest speed, m/s, at which the solver pushes overlapping bodies apart. #V0CAB5")

(defparameter *physics-load-stiffening* 100.0
  "Largest factor by which the load a contact with something static carries, as a mass over the
contact's effective mass, may divide the contact's impulse scale, and so its give at rest. #V0CAB5")

(defparameter *physics-crowded-relax-passes* 3
  "Extra relax passes per substep in a crowded step: one whose contacts needed the overflow
colour, or one after a step that left an overlap deeper than *physics-crowded-depth*. #V0CAB5")

(defparameter *physics-crowded-depth* 0.1
  "Overlap, m, beyond which the next step counts as crowded. #V0CAB5")

(defparameter *physics-linear-slop* 0.005
  "Penetration, m, allowed at rest; a resting ball sits this far into its support. #V0CAB5")

(defparameter *physics-speculative-margin* 0.1
  "Gap, m, under which a contact is made before touching (speculative contact). #V0CAB5")

(defparameter *physics-pair-skin* 0.03
  "Distance, m, beyond the widest reach within which the pair list keeps a pair, so that it holds
while no body strays from where it was built by more than about half this. #V0CAB5")

(defparameter *physics-restitution-threshold* 1.0
  "Approach speed, m/s, below which a contact does not bounce. #V0CAB5")

(defparameter *physics-hit-speed* 1.0
  "Approach speed, m/s, above which a pushing contact reports a hit. #V0CAB5")

(defparameter *physics-sleep-speed* 0.05
  "Speed, m/s, under which a body counts as still. #V0CAB5")

(defparameter *physics-time-to-sleep* 0.5
  "Seconds a body must stay still before it is put to sleep. #V0CAB5")

(defparameter *physics-wake-speed* 0.1
  "Speed, m/s, above which an awake body wakes the sleepers it reaches. #V0CAB5")

(defparameter *physics-brace-mass-ratio* 4.0
  "How many times heavier than a braced body another must be to lean on it as on something
static. #V0CAB5")

(defparameter *physics-reach-limit* 0.98
  "Largest reach (radius plus margin), in cells; it keeps every contact's cells adjacent. #V0CAB5")

(defparameter *physics-max-speed* 400.0
  "Speed, m/s, at which a body's velocity is clamped each substep. #V0CAB5")

(defparameter *physics-body-budget* 262144
  "Most bodies a world holds, awake and asleep together; an add beyond it is refused. #V0CAB5")

(defparameter *physics-terrain-chunk-budget* 32768
  "Most resident chunks (4 KB each) a terrain holds; a fill beyond it is refused. #V0CAB5")

(defconstant +physics-max-colors+ 24
  "Colours available to the constraint graph; colour 24 is the overflow colour. #V0CAB5")

(defconstant +physics-dynamic-colors+ 20
  "Colours 0..19 may take two-body contacts; one-sided contacts may take any of the 24. #V0CAB5")

(defconstant +physics-coordinate-limit+ 65536
  "Bodies live within this distance, in metres, of the origin on every axis. #V0CAB5")

(declaim (inline fsqrt))
(defun fsqrt (x)
  "The square root of the non-negative single-float X, as one SQRTSS (SBCL's own SQRT of a
single-float goes through double precision; both round correctly, so they agree). #V0CAB5"
  (declare (type single-float x))
  (sb-simd-sse::f32-sqrt x))

(declaim (inline store-clamped-velocity))
(defun store-clamped-velocity (v o x y z max-speed max2)
  "Store the velocity X Y Z in rows O..O+2 of V, scaled down to the speed MAX-SPEED when it is
faster (MAX2 is its square, computed once by the caller): the clamp every integration of
velocities ends with. #V0CAB5"
  (declare (type f32-column v) (type index o) (type single-float x y z max-speed max2))
  (let ((s2 (+ (* x x) (* y y) (* z z))))
    (when (> s2 max2)
      (let ((k (/ max-speed (fsqrt s2))))
        (setf x (* x k) y (* y k) z (* z k))))
    (setf (aref v o) x (aref v (+ o 1)) y (aref v (+ o 2)) z)))

(declaim (inline clock-ns))
(defun clock-ns ()
  "Nanoseconds on the monotonic clock (CLOCK_MONOTONIC, id 1 on Linux), as a fixnum. #V0CAB5"
  (multiple-value-bind (s ns) (sb-unix::clock-gettime 1)
    (declare (type (unsigned-byte 40) s) (type (unsigned-byte 31) ns))
    (+ (* s 1000000000) ns)))
;; Types, the hot-loop policy and the parameters:1 ends here

;; [[file:../physics.org::#C0ND1T][Bad input is a condition that names the value:1]]
(defconstant +physics-min-radius+ 0.005
  "Smallest radius, m, a body may have. #C0ND1T")

(defconstant +physics-max-radius+ 2.0
  "Largest radius, m, a sphere may have, and largest half-extent a box may have: two cells. #C0ND1T")

(defconstant +physics-min-mass+ 0.001
  "Smallest mass, kg, a body may have. #C0ND1T")

(defconstant +physics-max-mass+ 100000.0
  "Largest mass, kg, a body may have. #C0ND1T")

(defconstant +physics-max-friction+ 10.0
  "Largest friction or rolling-resistance coefficient a body may have. #C0ND1T")

(defconstant +physics-max-gravity+ 1000.0
  "Largest magnitude, m/s², of each component of a world's gravity. #C0ND1T")

(defconstant +physics-min-step-seconds+ 0.0001
  "Shortest step, s, a world may take. #C0ND1T")

(define-condition physics-error (error)
  ((world :initarg :world :initform nil :reader physics-error-world))
  (:documentation "Every error the engine signals for bad input; the world is left untouched. #C0ND1T"))

(define-condition invalid-physics-number (physics-error)
  ((name :initarg :name :reader invalid-physics-number-name)
   (value :initarg :value :reader invalid-physics-number-value))
  (:report (lambda (c s)
             (format s "~A must be a finite real number, not ~S"
                     (invalid-physics-number-name c) (invalid-physics-number-value c))))
  (:documentation "A NaN, an infinity or a non-number where a finite number is needed. #C0ND1T"))

(define-condition invalid-physics-radius (physics-error)
  ((value :initarg :value :reader invalid-physics-radius-value)
   (limit :initarg :limit :reader invalid-physics-radius-limit))
  (:report (lambda (c s)
             (format s "radius ~S is out of range: it must be from ~,3F to ~,3F, so that the ~
                        solver's arithmetic holds and a body spans at most four cells"
                     (invalid-physics-radius-value c) +physics-min-radius+ (invalid-physics-radius-limit c))))
  (:documentation "A radius of zero or less, or one over +physics-max-radius+. #C0ND1T"))

(define-condition invalid-physics-parameter (physics-error)
  ((name :initarg :name :reader invalid-physics-parameter-name)
   (value :initarg :value :reader invalid-physics-parameter-value)
   (expected :initarg :expected :reader invalid-physics-parameter-expected))
  (:report (lambda (c s)
             (format s "~A is ~S but must be ~A" (invalid-physics-parameter-name c)
                     (invalid-physics-parameter-value c) (invalid-physics-parameter-expected c))))
  (:documentation "A parameter outside its documented range: a mass <= 0, a negative friction. #C0ND1T"))

(define-condition not-a-physics-world (invalid-physics-parameter)
  ((operation :initarg :operation :reader not-a-physics-world-operation))
  (:report (lambda (c s)
             (format s "~(~A~): its argument ~A is ~S, not a physics-world (make one with ~
                        make-physics-world)" (not-a-physics-world-operation c)
                     (invalid-physics-parameter-name c) (invalid-physics-parameter-value c))))
  (:documentation "Something other than a world given to an exported function as its world. #C0ND1T"))

(define-condition stale-physics-handle (physics-error)
  ((handle :initarg :handle :reader stale-physics-handle-handle)
   (reason :initarg :reason :reader stale-physics-handle-reason))
  (:report (lambda (c s)
             (format s "handle ~S is ~A" (stale-physics-handle-handle c)
                     (ecase (stale-physics-handle-reason c)
                       (:malformed "not a physics handle")
                       (:foreign "from another world")
                       (:unissued "a handle of no world: no world has given out its tag")
                       (:removed "of a body that was removed or expired")))))
  (:documentation "A handle that names no live body of this world. #C0ND1T"))

(define-condition physics-body-in-solid-cell (invalid-physics-parameter)
  ((operation :initarg :operation :reader physics-body-in-solid-cell-operation)
   (cell :initarg :cell :reader physics-body-in-solid-cell-cell)
   (resident :initarg :resident :reader physics-body-in-solid-cell-resident)
   (part :initarg :part :initform "the centre" :reader physics-body-in-solid-cell-part))
  (:report (lambda (c s)
             (format s "~(~A~): ~A ~S lies in the ~:[non-resident~;solid~] cell ~S; a body starts ~
                        in an air cell of the resident terrain, or is added with :inside-cells :push-out ~
                        to be pushed out" (physics-body-in-solid-cell-operation c)
                     (physics-body-in-solid-cell-part c)
                     (invalid-physics-parameter-value c) (physics-body-in-solid-cell-resident c)
                     (physics-body-in-solid-cell-cell c))))
  (:documentation "A body placed with its centre in a solid cell, or in a chunk that is not
resident (which counts as solid), or a box with a corner there: PART says which, the centre or a
corner of the box centred at the position given, and CELL is that cell. #C0ND1T"))

(define-condition physics-world-busy (physics-error)
  ((operation :initarg :operation :reader physics-world-busy-operation))
  (:report (lambda (c s)
             (format s "~A was called while the world is stepping (from an event handler?); ~
                        make the change after step-physics-world returns"
                     (physics-world-busy-operation c))))
  (:documentation "An edit or a step attempted while a step is in flight. #C0ND1T"))

(define-condition physics-world-invalid (physics-error)
  ((invariant :initarg :invariant :reader physics-world-invalid-invariant))
  (:report (lambda (c s)
             (format s "physics world invariant broken: ~A" (physics-world-invalid-invariant c))))
  (:documentation "Signalled by validate-physics-world, naming the first broken invariant. #C0ND1T"))

(define-condition physics-budget-exceeded (physics-error)
  ((operation :initarg :operation :reader physics-budget-exceeded-operation)
   (resource :initarg :resource :reader physics-budget-exceeded-resource)
   (requested :initarg :requested :reader physics-budget-exceeded-requested)
   (budget :initarg :budget :reader physics-budget-exceeded-budget))
  (:report (lambda (c s)
             (format s "~(~A~) would need ~D ~(~A~), beyond the budget of ~D"
                     (physics-budget-exceeded-operation c) (physics-budget-exceeded-requested c)
                     (physics-budget-exceeded-resource c) (physics-budget-exceeded-budget c))))
  (:documentation "A request for more bodies, handles or terrain chunks than the documented
budget; signalled before anything is allocated. #C0ND1T"))

(declaim (inline finite-f32))
(defun finite-f32 (name value &optional world)
  "VALUE as a single-float, or an invalid-physics-number error naming NAME. #C0ND1T"
  ;; NaN first: comparing a NaN would itself trap
  (if (and (realp value)
           (not (and (floatp value) (sb-ext:float-nan-p value)))
           (< (abs value) most-positive-single-float))
      (coerce value 'single-float)
      (error 'invalid-physics-number :name name :value value :world world)))

(defun ranged-f32 (name value low high &optional world)
  "VALUE as a single-float from LOW to HIGH, or an error naming NAME: invalid-physics-number
when it is not finite, invalid-physics-parameter when it lies outside. #C0ND1T"
  (let ((v (finite-f32 name value world)))
    (unless (<= low v high)
      (error 'invalid-physics-parameter :world world :name name :value value
                                        :expected (format nil "from ~A to ~A" low high)))
    v))

(defun check-velocity (vx vy vz max-speed &optional world)
  "Signal invalid-physics-parameter naming :velocity unless the single-floats VX VY VZ make a
speed of at most MAX-SPEED. Each component is bounded first, so the square cannot overflow. #C0ND1T"
  (declare (type single-float vx vy vz max-speed))
  (unless (and (<= (abs vx) max-speed) (<= (abs vy) max-speed) (<= (abs vz) max-speed)
               (<= (+ (* vx vx) (* vy vy) (* vz vz)) (* max-speed max-speed)))
    (error 'invalid-physics-parameter :world world :name :velocity :value (list vx vy vz)
                                      :expected (format nil "a speed of at most ~A m/s" max-speed)))
  (values))

(defparameter +physics-parameters+
  '((:contact-hertz *physics-contact-hertz* 0 1000)
    (:contact-damping-ratio *physics-contact-damping-ratio* 0 1000)
    (:contact-push-max *physics-contact-push-max* 0 100)
    (:load-stiffening *physics-load-stiffening* 1 1000000)
    (:crowded-relax-passes *physics-crowded-relax-passes* 0 16 integer)
    (:crowded-depth *physics-crowded-depth* 0 1000000000)
    (:linear-slop *physics-linear-slop* 0 0.05)
    (:speculative-margin *physics-speculative-margin* 0 0.5)
    (:pair-skin *physics-pair-skin* 0 0.5)
    (:restitution-threshold *physics-restitution-threshold* 0 1000)
    (:hit-speed *physics-hit-speed* 0 1000)
    (:sleep-speed *physics-sleep-speed* 0 10)
    (:time-to-sleep *physics-time-to-sleep* 0 1000000)
    (:wake-speed *physics-wake-speed* 0 1000)
    (:brace-mass-ratio *physics-brace-mass-ratio* 1 1000000000)
    (:reach-limit *physics-reach-limit* 0.01 0.99)
    (:max-speed *physics-max-speed* 1 1000)
    (:body-budget *physics-body-budget* 1 #.(1- (ash 1 24)) integer))
  "Each parameter a world copies when it is made: its name, its special variable, the range it
must lie in, and INTEGER when it counts something. #C0ND1T")

(defun checked-physics-parameters ()
  "The current value of every parameter of +physics-parameters+, checked against its range, as
a plist by name (single-floats, or integers for counts); the speculative margin must also leave
room under the reach limit for the smallest radius. #C0ND1T"
  (let ((plist (loop for (name symbol low high kind) in +physics-parameters+
                     for value = (symbol-value symbol)
                     collect name
                     collect (if (eq kind 'integer)
                                 (if (and (integerp value) (<= low value high))
                                     value
                                     (error 'invalid-physics-parameter :name name :value value
                                                                       :expected (format nil "an integer from ~D to ~D" low high)))
                                 (ranged-f32 name value low high)))))
    (unless (>= (getf plist :reach-limit) (+ (getf plist :speculative-margin) +physics-min-radius+))
      (error 'invalid-physics-parameter :name :reach-limit :value (getf plist :reach-limit)
                                        :expected (format nil "at least the speculative margin plus ~A m" +physics-min-radius+)))
    plist))
;; Bad input is a condition that names the value:1 ends here

;; [[file:../physics.org::#L4Y0UT][One macro generates every columnar layout:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun layout-symbol (&rest parts)
    "Intern the concatenation of PARTS in the current package. #L4Y0UT"
    (intern (format nil "~{~A~}" parts)))
  (defun column-array-type (element-type)
    "The specialised array type that holds a column of ELEMENT-TYPE. #L4Y0UT"
    `(simple-array ,element-type (*)))
  (defun column-zero (element-type)
    "The zero of ELEMENT-TYPE. #L4Y0UT"
    (ecase element-type (single-float 0.0) (double-float 0d0) (fixnum 0)))
  (defun expand-layout-bindings (layout columns wanted buffer body)
    "The LET* that binds each WANTED column of BUFFER, a LAYOUT, as its declared array. #L4Y0UT"
    (let ((b (gensym "BUFFER")))
      `(let* ((,b ,buffer)
              ,@(loop for w in wanted
                      for var = (if (consp w) (first w) w)
                      for c = (if (consp w) (second w) w)
                      for spec = (or (find (symbol-name c) columns
                                           :key (lambda (s) (symbol-name (first s)))
                                           :test #'string=)
                                     (error "layout ~A has no column ~A" layout c))
                      collect `(,var (the ,(column-array-type (second spec)) (,(third spec) ,b)))))
         (declare (ignorable ,b))
         ,@body))))

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun layout-names (name)
    "The symbols the layout NAME defines, as a plist keyed by what each names. #L4Y0UT"
    (list :make (layout-symbol "%MAKE-" name)
          :ctor (layout-symbol "MAKE-" name)
          :len (layout-symbol name "-LENGTH")
          :cap (layout-symbol name "-CAPACITY")
          :spare (layout-symbol name "-SPARE")
          :ensure (layout-symbol name "-ENSURE-CAPACITY")
          :trim (layout-symbol name "-TRIM")
          :append (layout-symbol name "-APPEND")
          :remove (layout-symbol name "-SWAP-REMOVE")
          :copy (layout-symbol name "-COPY-ROW")
          :permute (layout-symbol name "-PERMUTE")
          :zero (layout-symbol name "-ZERO-ROW")
          :clear (layout-symbol name "-CLEAR")
          :with (layout-symbol "WITH-" name)
          :names (layout-symbol "+" name "-COLUMN-NAMES+")
          :bytes (layout-symbol "+" name "-ROW-BYTES+")))

  (defun layout-accessors (name columns)
    "The reader of each of COLUMNS in the layout NAME's struct, in their order. #L4Y0UT"
    (loop for (c) in columns collect (layout-symbol name "-" c))))
;; One macro generates every columnar layout:1 ends here

;; [[file:../physics.org::#L4Y0UT][One macro generates every columnar layout:2]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun layout-struct-forms (name docstring columns)
    "The struct of the layout NAME, one array slot per column of COLUMNS, and the constants that
name its columns and count a row's bytes. #L4Y0UT"
    (destructuring-bind (&key make names bytes &allow-other-keys) (layout-names name)
      `((defstruct (,name (:constructor ,make) (:copier nil) (:predicate nil))
          ,docstring
          (length 0 :type index)
          (capacity 0 :type index)
          (spare 0 :type index)
          ,@(loop for (c type) in columns
                  collect `(,c (make-array 0 :element-type ',type) :type ,(column-array-type type))))
        (defparameter ,names ',(mapcar #'first columns)
          ,(format nil "The columns of ~A, in declaration order. #L4Y0UT" name))
        (defparameter ,bytes ,(loop for (nil type width) in columns
                                    sum (* (or width 1) (ecase type (single-float 4) (double-float 8) (fixnum 8))))
          ,(format nil "Bytes one row of ~A occupies across its columns. #L4Y0UT" name)))))

  (defun layout-sizing-forms (name columns)
    "The layout NAME's constructor, and its operations that grow and shrink a buffer's arrays. #L4Y0UT"
    (destructuring-bind (&key make ctor len cap spare ensure trim &allow-other-keys) (layout-names name)
      (let ((accessors (layout-accessors name columns)))
        `((defun ,ctor (&key (capacity 16) (spare 0))
            ,(format nil "A new empty ~A buffer with room for CAPACITY rows plus SPARE zero rows. #L4Y0UT" name)
            (let ((size (+ capacity spare)))
              (,make :capacity capacity :spare spare
                     ,@(loop for (c type width) in columns
                             append `(,(intern (symbol-name c) :keyword)
                                      (make-array (* size ,(or width 1)) :element-type ',type
                                                                         :initial-element ,(column-zero type)))))))
          (defun ,ensure (buffer rows)
            ,(format nil "Grow BUFFER, a ~A, by doubling until it holds ROWS rows; return BUFFER. #L4Y0UT" name)
            (declare (type ,name buffer) (type index rows))
            (when (> rows (,cap buffer))
              (let* ((new (max rows (* 2 (,cap buffer)) 16))
                     (size (+ new (,spare buffer))))
                ,@(loop for (c type width) in columns for acc in accessors
                        collect `(let ((fresh (make-array (* size ,(or width 1)) :element-type ',type
                                                                                 :initial-element ,(column-zero type))))
                                   (replace fresh (,acc buffer))
                                   (setf (,acc buffer) fresh)))
                (setf (,cap buffer) new)))
            buffer)
          (defun ,trim (buffer rows)
            ,(format nil "Shrink BUFFER, a ~A, to room for ROWS rows, or for its length if that is more (and at
least 16), keeping every row; return BUFFER. #L4Y0UT" name)
            (declare (type ,name buffer) (type index rows))
            (let ((new (max rows (,len buffer) 16)))
              (when (< new (,cap buffer))
                (let ((size (+ new (,spare buffer))))
                  ,@(loop for (c type width) in columns for acc in accessors
                          collect `(let ((kept (make-array (* size ,(or width 1)) :element-type ',type
                                                                                  :initial-element ,(column-zero type))))
                                     (replace kept (,acc buffer))
                                     (setf (,acc buffer) kept)))
                  (setf (,cap buffer) new))))
            buffer))))))
;; One macro generates every columnar layout:2 ends here

;; [[file:../physics.org::#L4Y0UT][One macro generates every columnar layout:3]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun layout-row-forms (name columns)
    "The layout NAME's operations on one row: append one that reads as zeros, zero one, copy one
between buffers. #L4Y0UT"
    (destructuring-bind (&key len cap ensure append zero copy &allow-other-keys) (layout-names name)
      (let ((accessors (layout-accessors name columns)))
        `((declaim (inline ,append))
          (defun ,append (buffer)
            ,(format nil "Add a row to BUFFER, a ~A, and return its index; the row reads as zeros. #L4Y0UT" name)
            (declare (type ,name buffer))
            (let ((row (,len buffer)))
              (when (>= row (,cap buffer)) (,ensure buffer (1+ row)))
              (setf (,len buffer) (1+ row))
              row))
          (defun ,zero (buffer row)
            ,(format nil "Set every column of ROW of BUFFER, a ~A, to zero. #L4Y0UT" name)
            (declare (type ,name buffer) (type index row) #.+kernel-policy+)
            ,@(loop for (nil type width) in columns for acc in accessors
                    collect (if width
                                `(fill (,acc buffer) ,(column-zero type)
                                       :start (* row ,width) :end (* (1+ row) ,width))
                                `(setf (aref (,acc buffer) row) ,(column-zero type))))
            buffer)
          (defun ,copy (from from-row to to-row)
            ,(format nil "Copy row FROM-ROW of the ~A FROM into row TO-ROW of TO. #L4Y0UT" name)
            (declare (type ,name from to) (type index from-row to-row) #.+kernel-policy+)
            ,@(loop for (nil nil width) in columns for acc in accessors
                    collect (if width
                                `(replace (,acc to) (,acc from) :start1 (* to-row ,width)
                                                                 :start2 (* from-row ,width)
                                                                 :end2 (* (1+ from-row) ,width))
                                `(setf (aref (,acc to) to-row) (aref (,acc from) from-row))))
            to)))))

  (defun layout-permute-form (name columns)
    "The layout NAME's permute: every row to its new place, column by column through a scratch
buffer whose arrays it then takes. #L4Y0UT"
    (destructuring-bind (&key len cap ensure permute &allow-other-keys) (layout-names name)
      `(defun ,permute (buffer scratch destinations count &optional runner)
         ,(format nil "Move each row R of BUFFER, a ~A, to row (aref DESTINATIONS R), or drop it where
that is negative; the places taken must be exactly 0 .. COUNT-1. The rows are written into
SCRATCH, a buffer of the same layout and spare, whose arrays BUFFER then takes in exchange
for its own; rows past COUNT read as zeros. RUNNER, when given, is called with the move of the
rows FROM below TO, a function of the two, and the count of rows, and calls the move on
ranges that cover the rows once each, in any order. Return BUFFER. #L4Y0UT" name)
         (declare (type ,name buffer scratch) (type fixnum-column destinations) (type index count)
                  (type (or null function) runner) #.+kernel-policy+)
         (,ensure scratch (max count (,cap buffer)))
         (let ((n (,len buffer)) (stale (,len scratch)))
           (declare (type index n stale))
           ,@(loop for (nil type width) in columns for acc in (layout-accessors name columns)
                   collect (layout-permute-stale type width acc))
           (flet ((move (lo hi)
                    (declare (type index lo hi))
                    ,@(loop for (nil type width) in columns for acc in (layout-accessors name columns)
                            collect (layout-permute-column type width acc))))
             (declare (dynamic-extent #'move))
             (if runner (funcall runner #'move n) (move 0 n)))
           ,@(loop for acc in (layout-accessors name columns)
                   collect `(rotatef (,acc buffer) (,acc scratch)))
           (rotatef (,cap buffer) (,cap scratch))
           (setf (,len buffer) count (,len scratch) n))
         buffer)))

  (defun layout-permute-stale (type width acc)
    "Permute's clearing of one column of the scratch, read by ACC, of TYPE and WIDTH values a
row: the rows it held from its last use, past COUNT, become zeros. #L4Y0UT"
    `(let ((to (,acc scratch)))
       (declare (type ,(column-array-type type) to))
       (when (> stale count)
         (fill to ,(column-zero type) :start (* count ,(or width 1)) :end (* stale ,(or width 1))))))

  (defun layout-permute-column (type width acc)
    "Permute's pass over the rows LO below HI of one column, read by ACC, of TYPE and WIDTH values
a row. #L4Y0UT"
    `(let ((from (,acc buffer)) (to (,acc scratch)))
       (declare (type ,(column-array-type type) from to))
       (loop for r of-type index from lo below hi
             do (let ((d (aref destinations r)))
                  (declare (type fixnum d))
                  (when (>= d 0)
                    ,(if width
                         `(loop for k of-type fixnum from 0 below ,width
                                do (setf (aref to (+ (* d ,width) k))
                                         (aref from (+ (* r ,width) k))))
                         `(setf (aref to d) (aref from r)))))))))
;; One macro generates every columnar layout:3 ends here

;; [[file:../physics.org::#L4Y0UT][One macro generates every columnar layout:4]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun layout-removal-forms (name columns)
    "The layout NAME's swap-remove, which fills a hole with the last row, and clear. #L4Y0UT"
    (destructuring-bind (&key len spare remove copy zero clear &allow-other-keys) (layout-names name)
      `((defun ,remove (buffer row)
          ,(format nil "Remove ROW of BUFFER, a ~A, by moving the last row into it; the vacated
row is zeroed. Return the old index of the moved row, or -1 when ROW was last. #L4Y0UT" name)
          (declare (type ,name buffer) (type index row))
          (let ((last (1- (,len buffer))))
            (declare (type fixnum last))
            (assert (<= 0 row last) () "row ~D is outside ~A of length ~D" row ',name (1+ last))
            (unless (= row last) (,copy buffer last buffer row))
            (,zero buffer last)
            (setf (,len buffer) last)
            (if (= row last) -1 last)))
        (defun ,clear (buffer)
          ,(format nil "Empty BUFFER, a ~A, zeroing the rows it held. #L4Y0UT" name)
          (declare (type ,name buffer))
          (let ((n (+ (,len buffer) (,spare buffer))))
            ,@(loop for (nil type width) in columns for acc in (layout-accessors name columns)
                    collect `(fill (,acc buffer) ,(column-zero type)
                                   :end (min (* n ,(or width 1)) (length (,acc buffer))))))
          (setf (,len buffer) 0)
          buffer))))

  (defun layout-with-form (name columns)
    "The layout NAME's WITH- macro, binding columns by name as declared arrays. #L4Y0UT"
    (destructuring-bind (&key with &allow-other-keys) (layout-names name)
      `(defmacro ,with ((&rest cols) buffer &body body)
         ,(format nil "Run BODY with each of COLS bound to that column of the ~A BUFFER. #L4Y0UT" name)
         (expand-layout-bindings ',name ',(loop for (c type) in columns for acc in (layout-accessors name columns)
                                                collect (list c type acc))
                                 cols buffer body)))))

(defmacro define-physics-layout (name docstring &rest columns)
  "Define the columnar layout NAME: a buffer struct of one specialised array per column of
COLUMNS, each (COLUMN-NAME ELEMENT-TYPE), with NAME-append, NAME-swap-remove,
NAME-copy-row, NAME-permute, NAME-ensure-capacity, NAME-trim, NAME-clear and WITH-NAME, which binds columns by name
or as (VARIABLE COLUMN). A column (NAME TYPE WIDTH) holds WIDTH values a row, side by side. #L4Y0UT"
  `(progn
     ,@(layout-struct-forms name docstring columns)
     ,@(layout-sizing-forms name columns)
     ,@(layout-row-forms name columns)
     ,(layout-permute-form name columns)
     ,@(layout-removal-forms name columns)
     ,(layout-with-form name columns)
     ',name))
;; One macro generates every columnar layout:4 ends here

;; [[file:../physics.org::#B5N8JT][Bodies are rows; a handle is a forwarding address:1]]
(define-physics-layout body-columns
  "Bodies of one set (awake or sleeping), one specialised array per column. #B5N8JT"
  (x single-float) (y single-float) (z single-float)
  (vx single-float) (vy single-float) (vz single-float)
  (wx single-float) (wy single-float) (wz single-float)
  (qw single-float) (qx single-float) (qy single-float) (qz single-float)
  (radius single-float) (inverse-mass single-float) (inverse-inertia single-float)
  (restitution single-float) (friction single-float) (rolling-resistance single-float)
  (sleep-time single-float) (age double-float) (life single-float)
  (flags fixnum) (handle fixnum) (kind fixnum))

(defconstant +flag-report-hits+ 1 "Body flag: report :hit events for its hard arrivals. #B5N8JT")

(defconstant +flag-terrain-only+ 2 "Body flag: meets terrain and boxes but no other body. #B5N8JT")

(defconstant +flag-braced+ 4 "Body flag: braced at the last step that ran the bracing pass. #B5N8JT")

(defconstant +flag-box-shape+ 1024 "Body flag: the body is a box ([[#BXR0WS]]), not a sphere. #B5N8JT")

(defconstant +flag-filter-shift+ 16
  "Body flags: the place of the filter word ([[#F1LT3R]]), category from bit 16, mask from bit 32. #B5N8JT")

(defconstant +default-category+ 1 "The category of a body or box given none ([[#F1LT3R]]): the lowest bit alone. #B5N8JT")

(defconstant +all-categories+ #xFFFF "The mask of a body or box given none ([[#F1LT3R]]): all sixteen classes. #B5N8JT")

(defconstant +flag-column-steps+ (ash 63 3)
  "Body flags: the steps, up to 63, that it rested still on one support straight under it. #B5N8JT")

(defconstant +column-wait+ 30
  "Steps a body rests still on one support straight under it before it links a column. #B5N8JT")

(defconstant +column-look+ 8
  "Steps between the bracing passes of a world where no body can be static to another and no
column is forming: a pass at every such step finds a column that starts to form. #B5N8JT")

(defconstant +set-free+ 0 "Handle-table set of a free slot. #B5N8JT")

(defconstant +set-awake+ 1 "Handle-table set of an awake body. #B5N8JT")

(defconstant +set-sleeping+ 2 "Handle-table set of a sleeping body. #B5N8JT")

(defconstant +no-body+ -1 "The handle of no body: the other side of a one-sided contact. #B5N8JT")

(defconstant +handle-index-bits+ 24 "Bits of a handle that index the handle table. #B5N8JT")

(defconstant +handle-generation-bits+ 20 "Bits of a handle that count reuses of its slot. #B5N8JT")

(defconstant +handle-tag-bits+ 16 "Bits of a handle that name its world. #B5N8JT")

(defconstant +handle-joint-bit+ 60
  "The bit, above the tag, set in a joint's handle and in no body's ([[#J0STOR]]). #B5N8JT")

(declaim (inline handle-index handle-generation handle-tag make-handle))
(defun handle-index (handle)
  "The handle-table slot HANDLE names. #B5N8JT"
  (declare (type fixnum handle))
  (ldb (byte +handle-index-bits+ 0) handle))

(defun handle-generation (handle)
  "The generation HANDLE was issued with. #B5N8JT"
  (declare (type fixnum handle))
  (ldb (byte +handle-generation-bits+ +handle-index-bits+) handle))

(defun handle-tag (handle)
  "The tag of the world that issued HANDLE. #B5N8JT"
  (declare (type fixnum handle))
  (ldb (byte +handle-tag-bits+ (+ +handle-index-bits+ +handle-generation-bits+)) handle))

(defun make-handle (tag generation index)
  "The handle of slot INDEX at GENERATION in the world tagged TAG. #B5N8JT"
  (logior (ash tag (+ +handle-index-bits+ +handle-generation-bits+))
          (ash generation +handle-index-bits+)
          index))

(defstruct (handle-table (:constructor %make-handle-table))
  "The forwarding addresses: for each slot, the set and row of its body, and its generation. #B5N8JT"
  (set (make-array 16 :element-type 'fixnum :initial-element +set-free+) :type fixnum-column)
  (local (make-array 16 :element-type 'fixnum :initial-element -1) :type fixnum-column)
  (generation (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (count 0 :type index)
  (free -1 :type fixnum)
  (tag 0 :type fixnum))

(defvar *world-tag-counter* 0 "How many world tags have been given out; tags run from 1 to 2^16-1 and wrap. #B5N8JT")

(defun make-handle-table ()
  "An empty handle table with a fresh world tag, never 0. #B5N8JT"
  (%make-handle-table :tag (1+ (mod (1- (incf *world-tag-counter*)) (1- (ash 1 +handle-tag-bits+))))))

(defun tag-issued-p (tag)
  "True when some world has been given TAG. #B5N8JT"
  (and (plusp tag) (or (<= tag *world-tag-counter*) (>= *world-tag-counter* (1- (ash 1 +handle-tag-bits+))))))

(defun handle-table-allocate (table set local)
  "Take a free slot of TABLE for a body at SET and row LOCAL; return its new handle. #B5N8JT"
  (let ((slot (handle-table-free table)))
    (if (>= slot 0)
        (setf (handle-table-free table) (aref (handle-table-local table) slot))
        (progn
          (setf slot (handle-table-count table))
          (when (>= slot (length (handle-table-set table)))
            (let ((n (* 2 (length (handle-table-set table)))))
              (flet ((grow (a init) (let ((b (make-array n :element-type 'fixnum :initial-element init)))
                                      (replace b a) b)))
                (setf (handle-table-set table) (grow (handle-table-set table) +set-free+)
                      (handle-table-local table) (grow (handle-table-local table) -1)
                      (handle-table-generation table) (grow (handle-table-generation table) 0)))))
          (incf (handle-table-count table))))
    (setf (aref (handle-table-set table) slot) set
          (aref (handle-table-local table) slot) local)
    (make-handle (handle-table-tag table) (aref (handle-table-generation table) slot) slot)))

(defun handle-table-release (table handle)
  "Free the slot of HANDLE in TABLE and bump its generation, so HANDLE goes stale. #B5N8JT"
  (let ((slot (handle-index handle)))
    (setf (aref (handle-table-set table) slot) +set-free+
          (aref (handle-table-local table) slot) (handle-table-free table)
          (aref (handle-table-generation table) slot)
          (ldb (byte +handle-generation-bits+ 0) (1+ (aref (handle-table-generation table) slot)))
          (handle-table-free table) slot)
    table))

(defun handle-status (table handle)
  "NIL when HANDLE names a live body of TABLE, else why not (:malformed :unissued :foreign :removed). #B5N8JT"
  (cond ((not (and (typep handle 'fixnum) (>= handle 0))) :malformed)
        ((logbitp +handle-joint-bit+ handle) :malformed)
        ((/= (handle-tag handle) (handle-table-tag table))
         (if (tag-issued-p (handle-tag handle)) :foreign :unissued))
        ((or (>= (handle-index handle) (handle-table-count table))
             (= (aref (handle-table-set table) (handle-index handle)) +set-free+)
             (/= (aref (handle-table-generation table) (handle-index handle))
                 (handle-generation handle)))
         :removed)
        (t nil)))
;; Bodies are rows; a handle is a forwarding address:1 ends here

;; [[file:../physics.org::#H2W9DJ][Terrain: chunks of cells, and missing is a wall:1]]
(defconstant +chunk-bits+ 4 "A chunk is 2^4 = 16 cells along each axis. #H2W9DJ")


(defconstant +chunk-cells+ 4096 "Cells in a chunk. #H2W9DJ")

(defconstant +cell-limit+ (ash 1 22) "Cell coordinates must lie in (-2^22, 2^22). #H2W9DJ")

(deftype chunk-storage ()
  "The cells of one chunk, a byte each, nonzero when solid. #H2W9DJ"
  '(simple-array (unsigned-byte 8) (4096)))

(deftype cell ()
  "A cell coordinate. #H2W9DJ"
  '(integer #.(- (ash 1 22)) #.(ash 1 22)))

(defvar +wall-chunk+ (make-array +chunk-cells+ :element-type '(unsigned-byte 8) :initial-element 1)
  "The storage every non-resident chunk reads as: solid throughout. #H2W9DJ")

(defstruct (voxel-terrain (:constructor %make-voxel-terrain))
  "A lattice of unit cells in 16^3 chunks; a chunk that is not resident reads as solid. #H2W9DJ"
  (chunks (make-hash-table :test 'eql) :type hash-table)
  (lock 0 :type fixnum)
  (pending '() :type list)
  (pending-chunks (make-hash-table :test 'eql) :type hash-table)
  (pending-fill-chunks 0 :type fixnum)
  (edits 0 :type fixnum)
  (budget 0 :type fixnum))

(defun make-voxel-terrain ()
  "A terrain with no resident chunk: every cell reads as solid until a fill makes it resident.
It may hold *physics-terrain-chunk-budget* chunks, as that was when it was made. #H2W9DJ"
  (let ((budget *physics-terrain-chunk-budget*))
    (unless (and (integerp budget) (<= 1 budget (ash 1 24)))
      (error 'invalid-physics-parameter :name :terrain-chunk-budget :value budget
                                        :expected "an integer from 1 to 2^24"))
    (%make-voxel-terrain :budget budget)))

(defun check-chunk-room (terrain operation new)
  "Signal physics-budget-exceeded, naming OPERATION, when NEW more chunks would take TERRAIN past
its budget, counting the chunks its queued edits will make resident. #H2W9DJ"
  (let ((count (+ new (hash-table-count (voxel-terrain-chunks terrain))
                  (hash-table-count (voxel-terrain-pending-chunks terrain))
                  (voxel-terrain-pending-fill-chunks terrain))))
    (when (> count (voxel-terrain-budget terrain))
      (error 'physics-budget-exceeded :operation operation :resource :terrain-chunks
                                      :requested count :budget (voxel-terrain-budget terrain)))))

(declaim (inline chunk-key cell-offset))
(defun chunk-key (x y z)
  "The packed key of the chunk that holds cell X Y Z. #H2W9DJ"
  (declare (type cell x y z))
  (logior (ash (ldb (byte 19 0) (ash x (- +chunk-bits+))) 38)
          (ash (ldb (byte 19 0) (ash y (- +chunk-bits+))) 19)
          (ldb (byte 19 0) (ash z (- +chunk-bits+)))))

(defun cell-offset (x y z)
  "The index of cell X Y Z inside its chunk's storage. #H2W9DJ"
  (declare (type cell x y z))
  (logior (ldb (byte +chunk-bits+ 0) x)
          (ash (ldb (byte +chunk-bits+ 0) z) +chunk-bits+)
          (ash (ldb (byte +chunk-bits+ 0) y) (* 2 +chunk-bits+))))

(defun check-cell (name v)
  "V as a cell coordinate, or an error naming NAME. #H2W9DJ"
  (unless (and (integerp v) (< (- +cell-limit+) v +cell-limit+))
    (error 'invalid-physics-parameter :name name :value v
                                      :expected (format nil "an integer of magnitude under ~D" +cell-limit+)))
  v)

(declaim (inline check-terrain))
(defun check-terrain (terrain)
  "TERRAIN, a voxel-terrain, or an invalid-physics-parameter error naming :terrain. #H2W9DJ"
  (unless (voxel-terrain-p terrain)
    (error 'invalid-physics-parameter :name :terrain :value terrain :expected "a voxel-terrain"))
  terrain)

(defun terrain-solid-p (terrain x y z)
  "True when cell X Y Z of TERRAIN is solid; a cell of a non-resident chunk is solid. #H2W9DJ"
  (check-terrain terrain) (check-cell 'x x) (check-cell 'y y) (check-cell 'z z)
  (let ((chunk (gethash (chunk-key x y z) (voxel-terrain-chunks terrain))))
    (if chunk (plusp (aref (the chunk-storage chunk) (cell-offset x y z))) t)))

(defun terrain-resident-p (terrain x y z)
  "True when the chunk holding cell X Y Z of TERRAIN is resident. #H2W9DJ"
  (check-terrain terrain) (check-cell 'x x) (check-cell 'y y) (check-cell 'z z)
  (nth-value 1 (gethash (chunk-key x y z) (voxel-terrain-chunks terrain))))

(defun %resident-chunk (terrain x y z)
  "The storage of the chunk holding X Y Z, made resident (all air) if it was not and the budget
has room. #H2W9DJ"
  (let ((key (chunk-key x y z)) (table (voxel-terrain-chunks terrain)))
    (or (gethash key table)
        (setf (gethash key table)
              (progn (check-chunk-room terrain 'set-terrain-cell 1)
              (make-array +chunk-cells+ :element-type '(unsigned-byte 8) :initial-element 0))))))

(defun %set-cell (terrain x y z solid-p)
  "Write one cell, making its chunk resident. #H2W9DJ"
  (setf (aref (the chunk-storage (%resident-chunk terrain x y z)) (cell-offset x y z))
        (if solid-p 1 0))
  (incf (voxel-terrain-edits terrain)))

(defun (setf terrain-solid-p) (solid-p terrain x y z)
  "Make cell X Y Z of TERRAIN solid or air. During a step the edit waits for the step's end. #H2W9DJ"
  (check-terrain terrain) (check-cell 'x x) (check-cell 'y y) (check-cell 'z z)
  (let ((key (chunk-key x y z)))
    (unless (or (nth-value 1 (gethash key (voxel-terrain-chunks terrain)))
                (nth-value 1 (gethash key (voxel-terrain-pending-chunks terrain))))
      (check-chunk-room terrain '(setf terrain-solid-p) 1))
    (if (plusp (voxel-terrain-lock terrain))
        (setf (gethash key (voxel-terrain-pending-chunks terrain)) t
              (voxel-terrain-pending terrain) (cons (list x y z solid-p) (voxel-terrain-pending terrain)))
        (%set-cell terrain x y z solid-p)))
  solid-p)

(defun fill-terrain (terrain x0 y0 z0 x1 y1 z1 solid-p)
  "Set every cell of the half-open box [X0,X1)x[Y0,Y1)x[Z0,Z1) of TERRAIN to SOLID-P, making
the chunks it touches resident. Return TERRAIN. #H2W9DJ"
  (check-terrain terrain)
  (loop for (n v) on (list 'x0 x0 'y0 y0 'z0 z0 'x1 x1 'y1 y1 'z1 z1) by #'cddr do (check-cell n v))
  (when (and (< x0 x1) (< y0 y1) (< z0 z1))
    ;; count the chunks the box would make resident before making any
    (flet ((span (a b) (list (ash a (- +chunk-bits+)) (ash (1- b) (- +chunk-bits+)))))
      (destructuring-bind ((cx0 cx1) (cy0 cy1) (cz0 cz1)) (list (span x0 x1) (span y0 y1) (span z0 z1))
        (let ((touched (* (- cx1 cx0 -1) (- cy1 cy0 -1) (- cz1 cz0 -1)))
              (chunks (voxel-terrain-chunks terrain))
              (pending (voxel-terrain-pending-chunks terrain))
              (locked (plusp (voxel-terrain-lock terrain))))
          (when (> touched (voxel-terrain-budget terrain))
            (check-chunk-room terrain 'fill-terrain touched))
          (flet ((each-new-chunk (f)
                   ;; the chunks of the box neither resident nor made so by a queued edit
                   (loop for cx from cx0 to cx1
                         do (loop for cy from cy0 to cy1
                                  do (loop for cz from cz0 to cz1
                                           do (let ((key (chunk-key (ash cx +chunk-bits+) (ash cy +chunk-bits+)
                                                                    (ash cz +chunk-bits+))))
                                                (unless (or (nth-value 1 (gethash key chunks))
                                                            (nth-value 1 (gethash key pending)))
                                                  (funcall f key))))))))
            (let ((new 0))
              (declare (type fixnum new))
              (each-new-chunk (lambda (key) (declare (ignore key)) (incf new)))
              (check-chunk-room terrain 'fill-terrain new)
              ;; a step is in flight: the fill waits, and its new chunks count against the
              ;; budget until it is applied (counted, not noted one by one, so that queueing
              ;; a large fill conses nothing)
              (when locked
                (incf (voxel-terrain-pending-fill-chunks terrain) new))))))))
  (if (plusp (voxel-terrain-lock terrain))
      ;; a step is in flight: the whole fill waits as one edit
      (push (list :fill x0 y0 z0 x1 y1 z1 solid-p) (voxel-terrain-pending terrain))
      (%fill-cells terrain x0 y0 z0 x1 y1 z1 solid-p))
  terrain)

(defun %fill-cells (terrain x0 y0 z0 x1 y1 z1 solid-p)
  "Write every cell of the box [X0,X1)x[Y0,Y1)x[Z0,Z1), making its chunks resident. #H2W9DJ"
  (loop for x from x0 below x1 do
    (loop for y from y0 below y1 do
      (loop for z from z0 below z1 do
        (%set-cell terrain x y z solid-p)))))

(defun lock-terrain (terrain)
  "Mark TERRAIN as read by a step in flight; edits are queued until it is unlocked. #H2W9DJ"
  (incf (voxel-terrain-lock terrain)))

(defun unlock-terrain (terrain)
  "Release one lock on TERRAIN and apply the edits queued while it was locked, in order. #H2W9DJ"
  (when (zerop (decf (voxel-terrain-lock terrain)))
    (let ((edits (reverse (voxel-terrain-pending terrain))))
      (setf (voxel-terrain-pending terrain) '())
      (clrhash (voxel-terrain-pending-chunks terrain))
      (setf (voxel-terrain-pending-fill-chunks terrain) 0)
      (dolist (edit edits)
        (if (eq (first edit) :fill)
            (apply #'%fill-cells terrain (rest edit))
            (apply #'%set-cell terrain edit)))))
  terrain)

(defstruct (terrain-probe (:constructor make-terrain-probe))
  "Up to eight chunks' storage borrowed for one step, evicted round-robin. #H2W9DJ"
  (keys (make-array 8 :element-type 'fixnum :initial-element -1) :type fixnum-column)
  (chunks (make-array 8 :initial-element +wall-chunk+) :type simple-vector)
  (next 0 :type (integer 0 7))
  (terrain nil))

(defun reset-terrain-probe (probe terrain)
  "Forget every chunk PROBE borrowed and point it at TERRAIN. #H2W9DJ"
  (fill (terrain-probe-keys probe) -1)
  (fill (terrain-probe-chunks probe) +wall-chunk+)
  (setf (terrain-probe-next probe) 0
        (terrain-probe-terrain probe) terrain)
  probe)

(declaim (inline probe-chunk))
(defun probe-chunk (probe key)
  "The storage of the chunk with KEY, borrowed through PROBE. #H2W9DJ"
  (declare (type terrain-probe probe) (type fixnum key) #.+kernel-policy+)
  (let ((keys (terrain-probe-keys probe)))
    (dotimes (i 8 (%probe-miss probe key))
      (when (= (aref keys i) key)
        (return (svref (terrain-probe-chunks probe) i))))))

(defun %probe-miss (probe key)
  "Borrow the chunk with KEY into PROBE's next slot; a missing chunk borrows the wall. #H2W9DJ"
  (declare (type terrain-probe probe) (type fixnum key))
  (let ((chunk (or (gethash key (voxel-terrain-chunks (terrain-probe-terrain probe))) +wall-chunk+))
        (slot (terrain-probe-next probe)))
    (setf (aref (terrain-probe-keys probe) slot) key
          (svref (terrain-probe-chunks probe) slot) chunk
          (terrain-probe-next probe) (logand (1+ slot) 7))
    chunk))

(declaim (inline probe-solid-p))
(defun probe-solid-p (probe x y z)
  "True when cell X Y Z is solid, as PROBE sees the terrain this step. #H2W9DJ"
  (declare (type terrain-probe probe) (type cell x y z) #.+kernel-policy+)
  (plusp (aref (the chunk-storage (probe-chunk probe (chunk-key x y z))) (cell-offset x y z))))
;; Terrain: chunks of cells, and missing is a wall:1 ends here

;; [[file:../physics.org::#Y5H8KC][Contacts persist between steps, keyed by a packed pair:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +contact-fields+
    '(nx ny nz separation px py pz kvx kvy kvz normal-impulse tangent-impulse-1 tangent-impulse-2
      rolling-impulse-x rolling-impulse-y rolling-impulse-z spin-impulse)
    "The floats of a contact, side by side in its row of the geometry column, as wide as this
list is long. #Y5H8KC"))

(define-physics-layout contact-columns
  "Persistent contacts, one row per touching or nearly touching pair, keyed by a packed pair. #Y5H8KC"
  (handle-a fixnum) (handle-b fixnum) (kind fixnum) (key fixnum) (seen fixnum) (order fixnum)
  (touching fixnum) (geometry single-float #.(length +contact-fields+)))

(declaim (inline geometry-start))
(defun geometry-start (row)
  "Where the floats of contact ROW (one for each of +contact-fields+) begin in the geometry
column. #Y5H8KC"
  (declare (type index row))
  (the index (* row #.(length +contact-fields+))))

(defmacro contact-at (geometry start field)
  "The FIELD (one of +contact-fields+) of the contact whose floats begin at START (from
geometry-start) in the GEOMETRY column, the field's place folded into the address. #Y5H8KC"
  `(block-ref ,geometry ,start
              ,(or (position field +contact-fields+ :test #'string= :key #'symbol-name)
                   (error "no contact field ~A" field))))

(defmacro contact@ (geometry row field)
  "The FIELD (one of +contact-fields+) of contact ROW, an index, in the GEOMETRY column. #Y5H8KC"
  `(contact-at ,geometry (geometry-start ,row) ,field))

(defconstant +contact-pair+ 0 "Contact kind: two bodies. #Y5H8KC")

(defconstant +contact-terrain+ 1 "Contact kind: a body and a solid cell. #Y5H8KC")

(defconstant +contact-box+ 2 "Contact kind: a body and a posted kinematic box. #Y5H8KC")

(declaim (inline pair-key terrain-key box-key))
(defun pair-key (index-a index-b)
  "The key of the contact between the bodies in handle slots INDEX-A < INDEX-B. #Y5H8KC"
  (declare (type (unsigned-byte 24) index-a index-b))
  (logior (ash +contact-pair+ 58) (ash index-a 34) index-b))

(defun terrain-key (index x y z)
  "The key of the contact between the body in handle slot INDEX and cell X Y Z. #Y5H8KC"
  (declare (type (unsigned-byte 24) index) (type cell x y z))
  (logior (ash +contact-terrain+ 58) (ash index 34)
          (ash (ldb (byte 12 0) x) 22) (ash (ldb (byte 10 0) y) 12) (ldb (byte 12 0) z)))

(defun box-key (index box-id)
  "The key of the contact between the body in handle slot INDEX and box BOX-ID. #Y5H8KC"
  (declare (type (unsigned-byte 24) index) (type (unsigned-byte 34) box-id))
  (logior (ash +contact-box+ 58) (ash index 34) box-id))

(defstruct (contact-table (:constructor %make-contact-table))
  "An open-addressing map from contact key to contact row, with linear probing; slot I keeps
its key at 2I and its row at 2I+1, so a probe reads one cache line. It also keeps the step's
walk through the rows: the step being found (STEP), the row expected next (CURSOR), how many
rows have been found so far this step (TOUCHED), and how many finds the cursor failed to
predict since the rows were last put in order (MISSES). #Y5H8KC"
  (slots (make-array 128 :element-type 'fixnum :initial-element -1) :type fixnum-column)
  (mask 63 :type fixnum)
  (count 0 :type index)
  (step 0 :type fixnum)
  (cursor 0 :type index)
  (touched 0 :type index)
  (misses 0 :type index))

(defun make-contact-table () "An empty contact table. #Y5H8KC" (%make-contact-table))

(declaim (inline contact-slot-hash))
(defun contact-slot-hash (key mask)
  "The home slot of KEY in a table of MASK+1 slots. #Y5H8KC"
  (declare (type fixnum key mask) #.+kernel-policy+)
  (let* ((h (logxor key (ash key -29) (ash key -47)))
         (p (* (logand h #x1FFFFFFF) 2654435761)))
    (declare (type fixnum h) (type (unsigned-byte 62) p))
    (logand (ash p -13) mask)))

(defun contact-table-find (table key)
  "The contact row stored under KEY, or -1. #Y5H8KC"
  (declare (type contact-table table) (type fixnum key) #.+kernel-policy+)
  (let ((slots (contact-table-slots table)) (mask (contact-table-mask table)))
    (loop for i of-type fixnum = (contact-slot-hash key mask) then (logand (1+ i) mask)
          for k of-type fixnum = (aref slots (* 2 i))
          do (cond ((= k key) (return (aref slots (1+ (* 2 i)))))
                   ((= k -1) (return -1))))))

(defun contact-table-grow (table)
  "Double TABLE's slots and re-insert every entry. #Y5H8KC"
  (let* ((old (contact-table-slots table))
         (n (length old)))
    (setf (contact-table-slots table) (make-array (* 2 n) :element-type 'fixnum :initial-element -1)
          (contact-table-mask table) (1- n)
          (contact-table-count table) 0)
    (loop for i from 0 below n by 2
          unless (= (aref old i) -1) do (contact-table-put table (aref old i) (aref old (1+ i))))
    table))

(defun contact-table-put (table key row)
  "Map KEY to ROW in TABLE, adding or replacing the entry. #Y5H8KC"
  (declare (type contact-table table) (type fixnum key row))
  (when (>= (* 4 (1+ (contact-table-count table))) (length (contact-table-slots table)))
    (contact-table-grow table))
  (let ((slots (contact-table-slots table)) (mask (contact-table-mask table)))
    (loop for i of-type fixnum = (contact-slot-hash key mask) then (logand (1+ i) mask)
          for k of-type fixnum = (aref slots (* 2 i))
          do (cond ((= k key) (setf (aref slots (1+ (* 2 i))) row) (return))
                   ((= k -1)
                    (setf (aref slots (* 2 i)) key (aref slots (1+ (* 2 i))) row)
                    (incf (contact-table-count table))
                    (return)))))
  table)

(defun contact-table-delete (table key)
  "Remove KEY from TABLE, shifting later entries of its probe run back so no tombstone is left. #Y5H8KC"
  (declare (type contact-table table) (type fixnum key) #.+kernel-policy+)
  (let* ((slots (contact-table-slots table))
         (mask (contact-table-mask table))
         (i (loop for i of-type fixnum = (contact-slot-hash key mask) then (logand (1+ i) mask)
                  for k of-type fixnum = (aref slots (* 2 i))
                  do (cond ((= k key) (return i)) ((= k -1) (return -1))))))
    (declare (type fixnum i))
    (when (>= i 0)
      (decf (contact-table-count table))
      (loop with hole of-type fixnum = i
            for j of-type fixnum = (logand (1+ hole) mask) then (logand (1+ j) mask)
            for k of-type fixnum = (aref slots (* 2 j))
            do (when (= k -1)
                 (setf (aref slots (* 2 hole)) -1 (aref slots (1+ (* 2 hole))) -1)
                 (return))
               (let ((home (contact-slot-hash k mask)))
                 ;; move K back into the hole unless its home lies cyclically in (hole, j]
                 (unless (if (<= hole j) (and (< hole home) (<= home j)) (or (< hole home) (<= home j)))
                   (setf (aref slots (* 2 hole)) k (aref slots (1+ (* 2 hole))) (aref slots (1+ (* 2 j)))
                         hole j)))))
    table))
;; Contacts persist between steps, keyed by a packed pair:1 ends here

;; [[file:../physics.org::#D9W4CH][The block world is the static tree; bodies need a hash grid:1]]
(defstruct (hash-grid (:constructor make-hash-grid))
  "Items bucketed by the cell of their centre, counting-sorted so a cell's items are one run.
When the items' cells fill a small enough box, the buckets are that box's cells themselves
(DENSE), x fastest; otherwise they are hashed. NEAR is scratch room: the build keeps each
item's bucket there, and a walk lists the entries it keeps. #D9W4CH"
  (inv-cell 1.0 :type single-float)
  (count 0 :type index)
  (mask 0 :type fixnum)
  (dense nil :type boolean)
  (ox 0 :type fixnum) (oy 0 :type fixnum) (oz 0 :type fixnum)
  (nx 1 :type fixnum) (ny 1 :type fixnum) (nz 1 :type fixnum)
  (starts (make-array 2 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (items (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (keys (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (item-keys (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (xs (make-array 0 :element-type 'single-float) :type f32-column)
  (ys (make-array 0 :element-type 'single-float) :type f32-column)
  (zs (make-array 0 :element-type 'single-float) :type f32-column)
  (near (make-array 0 :element-type 'fixnum) :type fixnum-column))

(declaim (inline cell-floor grid-cell-key grid-bucket))
(defun cell-floor (v)
  "The integer floor of V, clamped to the range a cell coordinate may take. #D9W4CH"
  (declare (type single-float v) #.+kernel-policy+)
  (let* ((c (max -4.0e6 (min 4.0e6 v)))
         (i (truncate c)))
    (declare (type (single-float -4.0e6 4.0e6) c) (type fixnum i))
    (if (< c (float i 1.0)) (1- i) i)))

(defun grid-cell-key (cx cy cz)
  "The packed key of grid cell CX CY CZ (each taken modulo 2^20). #D9W4CH"
  (declare (type fixnum cx cy cz))
  (logior (ash (ldb (byte 20 0) cx) 40) (ash (ldb (byte 20 0) cy) 20) (ldb (byte 20 0) cz)))

(defun grid-bucket (key mask)
  "The bucket of cell KEY in a grid of MASK+1 buckets. #D9W4CH"
  (declare (type fixnum key mask) #.+kernel-policy+)
  (let* ((h (logxor key (ash key -21) (ash key -43)))
         (p (* (logand h #x1FFFFFFF) 2654435761)))
    (declare (type fixnum h) (type (unsigned-byte 62) p))
    (logand (ash p -11) mask)))
;; The block world is the static tree; bodies need a hash grid:1 ends here

;; [[file:../physics.org::#D9W4CH][The block world is the static tree; bodies need a hash grid:2]]
(declaim (type (integer 0 1024) *physics-dense-grid-cells*))
(defparameter *physics-dense-grid-cells* 64
  "The most cells per item the box of a dense grid may have; a larger box is hashed. #D9W4CH")

(declaim (inline dense-limit))
(defun dense-limit (count)
  "The most cells a dense grid of COUNT items may have: *physics-dense-grid-cells* per item,
plus 64. #D9W4CH"
  (declare (type index count))
  (+ 64 (* *physics-dense-grid-cells* count)))

(declaim (inline hashed-buckets))
(defun hashed-buckets (count)
  "The buckets of a hashed grid of COUNT items: a power of two, at least twice COUNT and 16. #D9W4CH"
  (declare (type index count))
  (max 16 (ash 1 (integer-length (* 2 count)))))

(defun hash-grid-reserve (grid n)
  "Give GRID room for N items, hashed, so that building it with at most N items allocates
nothing; return GRID. #D9W4CH"
  (declare (type hash-grid grid) (type index n))
  (when (< (length (hash-grid-items grid)) n)
    (let ((m (max n (* 2 (length (hash-grid-items grid))))))
      ;; centres and the near list keep four spare places for the four-lane listing
      (setf (hash-grid-items grid) (make-array m :element-type 'fixnum)
            (hash-grid-keys grid) (make-array m :element-type 'fixnum)
            (hash-grid-item-keys grid) (make-array m :element-type 'fixnum)
            (hash-grid-xs grid) (make-array (+ m 4) :element-type 'single-float :initial-element 0.0)
            (hash-grid-ys grid) (make-array (+ m 4) :element-type 'single-float :initial-element 0.0)
            (hash-grid-zs grid) (make-array (+ m 4) :element-type 'single-float :initial-element 0.0)
            (hash-grid-near grid) (make-array (+ m 4) :element-type 'fixnum :initial-element 0))))
  (when (< (length (hash-grid-starts grid)) (1+ (hashed-buckets n)))
    (setf (hash-grid-starts grid) (make-array (1+ (hashed-buckets n)) :element-type 'fixnum)))
  grid)

(defun hash-grid-trim (grid)
  "Shrink GRID's arrays to what its entries and buckets use, keeping every entry in its place;
return GRID. #D9W4CH"
  (declare (type hash-grid grid))
  (let* ((n (hash-grid-count grid))
         (buckets (if (hash-grid-dense grid)
                      (* (hash-grid-nx grid) (hash-grid-ny grid) (hash-grid-nz grid))
                      (1+ (hash-grid-mask grid)))))
    (flet ((kept (array length)
             (if (> (length array) length) (subseq array 0 length) array)))
      (setf (hash-grid-items grid) (kept (hash-grid-items grid) n)
            (hash-grid-keys grid) (kept (hash-grid-keys grid) n)
            (hash-grid-item-keys grid) (kept (hash-grid-item-keys grid) n)
            ;; the centres and the near list keep four spare places for the four-lane listing
            (hash-grid-xs grid) (kept (hash-grid-xs grid) (+ n 4))
            (hash-grid-ys grid) (kept (hash-grid-ys grid) (+ n 4))
            (hash-grid-zs grid) (kept (hash-grid-zs grid) (+ n 4))
            (hash-grid-near grid) (kept (hash-grid-near grid) (+ n 4))
            (hash-grid-starts grid) (kept (hash-grid-starts grid) (max 2 (1+ buckets))))))
  grid)
;; The block world is the static tree; bodies need a hash grid:2 ends here

;; [[file:../physics.org::#D9W4CH][The block world is the static tree; bodies need a hash grid:3]]
(defun build-hash-grid (grid cell-size n xs ys zs ids &key (dense-allowed t))
  "Bucket N items with centres XS YS ZS and identities IDS (row or handle) into GRID: densely
when DENSE-ALLOWED and the box of their cells, one cell of padding around, has at most
(dense-limit N) cells, else by hash. The grid keeps its own copy of the centres in its order,
so a walk over neighbouring cells reads positions from one run of memory. #D9W4CH"
  (declare (type hash-grid grid) (type single-float cell-size) (type index n)
           (type f32-column xs ys zs) (type fixnum-column ids) #.+kernel-policy+)
  (let ((inv (/ 1.0 cell-size)))
    (when (< (length (hash-grid-items grid)) n)
      (hash-grid-reserve grid n))
    (setf (hash-grid-inv-cell grid) inv (hash-grid-count grid) n)
    ;; the box of occupied cells decides the mode
    (let ((x0 most-positive-fixnum) (y0 most-positive-fixnum) (z0 most-positive-fixnum)
          (x1 most-negative-fixnum) (y1 most-negative-fixnum) (z1 most-negative-fixnum))
      (declare (type fixnum x0 y0 z0 x1 y1 z1))
      ;; each item's cell key is kept, so the second pass finds its cell without flooring again
      (let ((item-keys (hash-grid-item-keys grid)))
        (dotimes (i n)
          (let ((cx (cell-floor (* (aref xs i) inv))) (cy (cell-floor (* (aref ys i) inv)))
                (cz (cell-floor (* (aref zs i) inv))))
            (setf (aref item-keys i) (grid-cell-key cx cy cz)
                  x0 (min x0 cx) x1 (max x1 cx) y0 (min y0 cy) y1 (max y1 cy) z0 (min z0 cz) z1 (max z1 cz)))))
      (let* ((nx (if (plusp n) (+ 3 (- x1 x0)) 1)) (ny (if (plusp n) (+ 3 (- y1 y0)) 1))
             (nz (if (plusp n) (+ 3 (- z1 z0)) 1))
             (cells (if (and (< nx 4096) (< ny 4096) (< nz 4096)) (* nx ny nz) most-positive-fixnum))
             (dense (and dense-allowed (plusp n) (<= cells (dense-limit n))))
             (buckets (if dense cells (hashed-buckets n)))
             (mask (1- buckets)))
        (declare (type fixnum nx ny nz cells buckets mask))
        (setf (hash-grid-dense grid) dense (hash-grid-mask grid) mask
              (hash-grid-ox grid) (1- x0) (hash-grid-oy grid) (1- y0) (hash-grid-oz grid) (1- z0)
              (hash-grid-nx grid) nx (hash-grid-ny grid) ny (hash-grid-nz grid) nz)
        ;; a dense box that outgrows the buckets takes at once the room of the largest box
        ;; the bound allows at this item capacity, so a box that keeps growing (drops
        ;; spreading from a fountain) reallocates once, not at every doubling
        (when (< (length (hash-grid-starts grid)) (1+ buckets))
          (setf (hash-grid-starts grid)
                (make-array (max (1+ buckets) (* 2 (length (hash-grid-starts grid)))
                                 (if dense (1+ (dense-limit (length (hash-grid-items grid)))) 0))
                            :element-type 'fixnum)))
        (let ((starts (hash-grid-starts grid)) (items (hash-grid-items grid))
              (keys (hash-grid-keys grid)) (item-keys (hash-grid-item-keys grid))
              (item-buckets (hash-grid-near grid))
              (gx (hash-grid-xs grid)) (gy (hash-grid-ys grid)) (gz (hash-grid-zs grid))
              (ox (1- x0)) (oy (1- y0)) (oz (1- z0)))
          (declare (type fixnum ox oy oz))
          ;; a dense box is under 4096 cells a side, so a cell's offsets in it are the
          ;; differences of the key's 20-bit fields from the corner's, taken modulo 2^20
          (flet ((dense-bucket (key)
                   (declare (type fixnum key))
                   (flet ((offset (field corner)
                            (declare (type (unsigned-byte 20) field) (type fixnum corner))
                            (the (integer 0 4095) (logand (- field (ldb (byte 20 0) corner)) #xFFFFF))))
                     (declare (inline offset))
                     (+ (offset (ldb (byte 20 40) key) ox)
                        (* (the (integer 1 4096) nx)
                           (+ (offset (ldb (byte 20 20) key) oy)
                              (* (the (integer 1 4096) ny) (offset (ldb (byte 20 0) key) oz))))))))
            (declare (inline dense-bucket))
          (fill starts 0 :end (1+ buckets))
          ;; the bucket of each item: its cell's index in the box, or its hashed cell key
          (dotimes (i n)
            (let* ((key (aref item-keys i))
                   (bucket (if dense (dense-bucket key) (grid-bucket key mask))))
              (declare (type fixnum bucket))
              (setf (aref item-buckets i) bucket)
              (incf (aref starts (1+ bucket)))))
          (loop for b of-type fixnum from 1 to buckets
                do (incf (aref starts b) (aref starts (1- b))))
          ;; place items by decrementing the end of their bucket, walking backwards, so each
          ;; bucket lists its items in increasing order
          (loop for i of-type fixnum from (1- n) downto 0
                do (let* ((key (aref item-keys i))
                          (b (1+ (aref item-buckets i)))
                          (at (decf (aref starts b))))
                     (setf (aref items at) (aref ids i) (aref keys at) key
                           (aref gx at) (aref xs i) (aref gy at) (aref ys i) (aref gz at) (aref zs i))))
          ;; now starts[b+1] is the beginning of bucket b; shift so starts[b] begins bucket b
          (replace starts starts :start1 0 :start2 1 :end2 (1+ buckets))
          (setf (aref starts buckets) n)))))
    grid))
;; The block world is the static tree; bodies need a hash grid:3 ends here

;; [[file:../physics.org::#D9W4CH][The block world is the static tree; bodies need a hash grid:4]]
(defmacro do-dense-grid-runs ((entry grid) (i0 j0 k0 i1 j1 k1) &body body)
  "Run BODY with ENTRY bound to each place of the dense GRID's order whose cell lies from I0 J0 K0
to I1 J1 K1 (fixnums), cut to the grid's own box: layer by layer along z, row by row along y,
each row of cells along x one run of places. #D9W4CH"
  (let ((g (gensym "GRID")) (starts (gensym "STARTS")) (ox (gensym "OX")) (oy (gensym "OY"))
        (oz (gensym "OZ")) (nx (gensym "NX")) (ny (gensym "NY")) (nz (gensym "NZ"))
        (lo (gensym "LO")) (hi (gensym "HI")) (j (gensym "J")) (k (gensym "K")) (row (gensym "ROW")))
    `(let* ((,g ,grid) (,starts (hash-grid-starts ,g))
            (,ox (hash-grid-ox ,g)) (,oy (hash-grid-oy ,g)) (,oz (hash-grid-oz ,g))
            (,nx (hash-grid-nx ,g)) (,ny (hash-grid-ny ,g)) (,nz (hash-grid-nz ,g))
            (,lo (max ,ox ,i0)) (,hi (min (+ ,ox ,nx -1) ,i1)))
       ;; a dense grid's box is under 4096 cells a side
       (declare (type fixnum-column ,starts) (type cell ,ox ,oy ,oz)
                (type (integer 1 4096) ,nx ,ny ,nz) (type fixnum ,lo ,hi))
       (when (<= ,lo ,hi)
         (loop for ,k of-type fixnum from (max ,oz ,k0) to (min (+ ,oz ,nz -1) ,k1) do
           (loop for ,j of-type fixnum from (max ,oy ,j0) to (min (+ ,oy ,ny -1) ,j1)
                 for ,row of-type fixnum = (* ,nx (+ (- ,j ,oy) (* ,ny (- ,k ,oz))))
                 do (loop for ,entry of-type fixnum from (aref ,starts (+ ,row (- ,lo ,ox)))
                            below (aref ,starts (+ ,row (- ,hi ,ox) 1))
                          do (progn ,@body))))))))

(defmacro do-hashed-grid-cells ((entry grid) (i0 j0 k0 i1 j1 k1) &body body)
  "Run BODY with ENTRY bound to each place of the hashed GRID's order whose cell lies from I0 J0
K0 to I1 J1 K1 (fixnums), cell by cell in the order z, y, x: each cell's key names a bucket,
and of the bucket's places those of that key belong. #D9W4CH"
  (let ((g (gensym "GRID")) (starts (gensym "STARTS")) (keys (gensym "KEYS")) (mask (gensym "MASK"))
        (i (gensym "I")) (j (gensym "J")) (k (gensym "K")) (key (gensym "KEY")) (b (gensym "B")))
    `(let* ((,g ,grid) (,starts (hash-grid-starts ,g)) (,keys (hash-grid-keys ,g))
            (,mask (hash-grid-mask ,g)))
       (declare (type fixnum-column ,starts ,keys) (type fixnum ,mask))
       (loop for ,k of-type fixnum from ,k0 to ,k1 do
         (loop for ,j of-type fixnum from ,j0 to ,j1 do
           (loop for ,i of-type fixnum from ,i0 to ,i1
                 for ,key of-type fixnum = (grid-cell-key ,i ,j ,k)
                 for ,b of-type fixnum = (grid-bucket ,key ,mask)
                 do (loop for ,entry of-type fixnum from (aref ,starts ,b) below (aref ,starts (1+ ,b))
                          when (= (aref ,keys ,entry) ,key)
                            do (progn ,@body))))))))

(defmacro do-grid-entries ((entry grid) (i0 j0 k0 i1 j1 k1) &body body)
  "Run BODY with ENTRY bound to the place, in GRID's order, of each item bucketed in a cell from
I0 J0 K0 to I1 J1 K1 (cell coordinates, fixnums), cell by cell in the order z, y, x, the dense
grid's way or the hashed grid's. The bounds are read once, before any cell. #D9W4CH"
  (let ((g (gensym "GRID")) (visit (gensym "VISIT")) (e (gensym "E"))
        (box (loop for name in '("I0" "J0" "K0" "I1" "J1" "K1") collect (gensym name))))
    `(let ((,g ,grid) ,@(mapcar #'list box (list i0 j0 k0 i1 j1 k1)))
       (declare (type fixnum ,@box))
       (flet ((,visit (,entry) (declare (type index ,entry) (ignorable ,entry)) ,@body))
         (declare (inline ,visit))
         (cond ((zerop (hash-grid-count ,g)))
               ((hash-grid-dense ,g) (do-dense-grid-runs (,e ,g) ,box (,visit ,e)))
               (t (do-hashed-grid-cells (,e ,g) ,box (,visit ,e))))))))

(defmacro do-grid-cells (((item &optional entry) grid) (i0 j0 k0 i1 j1 k1) &body body)
  "Run BODY with ITEM bound to each item of GRID bucketed in a cell from I0 J0 K0 to I1 J1 K1 (cell
coordinates, fixnums), cell by cell in the order z, y, x (do-grid-entries); ENTRY, when given,
is bound to the item's place in the grid's order, where the grid keeps its copy of the item's
centre. #D9W4CH"
  (let ((g (gensym "GRID")) (items (gensym "ITEMS")) (entry (or entry (gensym "ENTRY"))))
    `(let* ((,g ,grid) (,items (hash-grid-items ,g)))
       (declare (type fixnum-column ,items))
       (do-grid-entries (,entry ,g) (,i0 ,j0 ,k0 ,i1 ,j1 ,k1)
         (let ((,item (aref ,items ,entry)))
           (declare (type fixnum ,item) (ignorable ,item))
           ,@body)))))

(defmacro do-grid-neighbours ((item grid x y z &key (span 1)) &body body)
  "Run BODY with ITEM bound to each item of GRID whose cell lies within SPAN cells of the cell
of point X Y Z, cell by cell in a fixed order (do-grid-cells). #D9W4CH"
  (let ((g (gensym "GRID")) (cx (gensym)) (cy (gensym)) (cz (gensym)) (inv (gensym)) (s (gensym)))
    `(let* ((,g ,grid) (,inv (hash-grid-inv-cell ,g)) (,s (min ,span ,(ash 1 22)))
            (,cx (cell-floor (* ,x ,inv))) (,cy (cell-floor (* ,y ,inv))) (,cz (cell-floor (* ,z ,inv))))
       (declare (type cell ,cx ,cy ,cz) (type (integer 0 ,(ash 1 22)) ,s))
       (do-grid-cells ((,item) ,g) ((- ,cx ,s) (- ,cy ,s) (- ,cz ,s) (+ ,cx ,s) (+ ,cy ,s) (+ ,cz ,s))
         ,@body))))
;; The block world is the static tree; bodies need a hash grid:4 ends here

;; [[file:../physics.org::#D9W4CH][The block world is the static tree; bodies need a hash grid:5]]
(defun grid-half-runs (grid entry runs)
  "Fill RUNS with the half neighbourhood of the cell of ENTRY, a place in GRID's order, as
triples (start end key) of places, and return how many triples. The first run starts at
ENTRY+1 and covers the rest of the cell's own items (in a dense grid, the next cell along x
too); the others cover the cells after it in the order z, y, x. A KEY of -1 means every item
of the run belongs; otherwise (a hashed grid, whose runs are buckets) only items whose cell key
is KEY do. #D9W4CH"
  (declare (type hash-grid grid) (type index entry) (type fixnum-column runs) #.+kernel-policy+)
  (let* ((inv (hash-grid-inv-cell grid)) (starts (hash-grid-starts grid))
         (cx (cell-floor (* (aref (hash-grid-xs grid) entry) inv)))
         (cy (cell-floor (* (aref (hash-grid-ys grid) entry) inv)))
         (cz (cell-floor (* (aref (hash-grid-zs grid) entry) inv)))
         (n 0))
    (declare (type fixnum cx cy cz n))
    (flet ((run (start end key)
             (declare (type fixnum start end key))
             (setf (aref runs (* 3 n)) start (aref runs (+ (* 3 n) 1)) end (aref runs (+ (* 3 n) 2)) key)
             (incf n)))
      (declare (inline run))
      (if (hash-grid-dense grid)
          ;; an occupied cell is at least one cell inside the padded box, so its neighbours are too
          (let* ((nx (the (integer 1 4096) (hash-grid-nx grid)))
                 (nxy (* nx (the (integer 1 4096) (hash-grid-ny grid))))
                 (c (+ (- cx (the cell (hash-grid-ox grid)))
                       (* nx (- cy (the cell (hash-grid-oy grid)))) (* nxy (- cz (the cell (hash-grid-oz grid)))))))
            (declare (type index c))
            (run (1+ entry) (aref starts (+ c 2)) -1)
            (let ((r (+ c nx -1))) (run (aref starts r) (aref starts (+ r 3)) -1))
            (loop for dy of-type fixnum from -1 to 1
                  do (let ((r (+ c nxy (* dy nx) -1))) (run (aref starts r) (aref starts (+ r 3)) -1))))
          (let ((mask (hash-grid-mask grid)))
            (flet ((cell (i j k)
                     (declare (type fixnum i j k))
                     (let* ((key (grid-cell-key i j k)) (b (grid-bucket key mask)))
                       (run (aref starts b) (aref starts (1+ b)) key))))
              (declare (inline cell))
              (let* ((key (grid-cell-key cx cy cz)) (b (grid-bucket key mask)))
                (run (1+ entry) (aref starts (1+ b)) key))
              (cell (1+ cx) cy cz)
              (loop for i of-type fixnum from (1- cx) to (1+ cx) do (cell i (1+ cy) cz))
              (loop for j of-type fixnum from (1- cy) to (1+ cy)
                    do (loop for i of-type fixnum from (1- cx) to (1+ cx) do (cell i j (1+ cz))))))))
    n))

(declaim (type (simple-array fixnum (64)) +lane-compress+))
(sb-ext:defglobal +lane-compress+
  (let ((table (make-array 64 :element-type 'fixnum :initial-element 0)))
    (dotimes (mask 16 table)
      (let ((k 0))
        (dotimes (lane 4)
          (when (logbitp lane mask)
            (setf (aref table (+ (* 4 mask) k)) lane)
            (incf k))))))
  "For each 4-bit lane mask, its set lanes in rising order, four entries a mask. #D9W4CH")

(defun grid-list-near (grid entry runs run-count reach2 &optional (near (hash-grid-near grid)))
  "List in NEAR (GRID's own column unless a worker gives its own) the places of the RUN-COUNT
RUNS (as grid-half-runs fills them for ENTRY) whose centres lie closer than the square root of
REACH2 to the centre of ENTRY, in run order, and return how many. The list grows by the sign bit of the squared distance minus
REACH2, so the test costs no branch; a dense grid's runs are tested four places at a time.
#D9W4CH"
  (declare (type hash-grid grid) (type index entry) (type fixnum-column runs)
           (type (integer 0 14) run-count) (type single-float reach2) (type fixnum-column near)
           #.+kernel-policy+)
  (let* ((gx (hash-grid-xs grid)) (gy (hash-grid-ys grid)) (gz (hash-grid-zs grid))
         (keys (hash-grid-keys grid))
         (x (aref gx entry)) (y (aref gy entry)) (z (aref gz entry))
         ;; the table in a local, read once a call, not once a lane
         (compress +lane-compress+)
         (found 0))
    (declare (type index found))
    (flet ((within (f)
             (declare (type index f))
             (let ((dx (- (aref gx f) x)) (dy (- (aref gy f) y)) (dz (- (aref gz f) z)))
               (ldb (byte 1 31) (sb-kernel:single-float-bits (- (+ (* dx dx) (* dy dy) (* dz dz)) reach2))))))
      (declare (inline within))
      (dotimes (q run-count)
        (let ((start (if (= q 0) (1+ entry) (aref runs (* 3 q))))
              (end (aref runs (+ (* 3 q) 1)))
              (key (aref runs (+ (* 3 q) 2))))
          (declare (type index start end) (type fixnum key))
          (if (= key -1)
              ;; four at a time: the signs of four squared distances minus the reach, masked
              ;; to the run, pick the lanes that +lane-compress+ writes, in order
              (let ((x4 (sb-simd-sse:f32.4 x)) (y4 (sb-simd-sse:f32.4 y)) (z4 (sb-simd-sse:f32.4 z))
                    (r4 (sb-simd-sse:f32.4 reach2)))
                (loop for f of-type index from start below end by 4
                      do (let* ((dx (sb-simd-sse:f32.4- (sb-simd-sse:f32.4-aref gx f) x4))
                                (dy (sb-simd-sse:f32.4- (sb-simd-sse:f32.4-aref gy f) y4))
                                (dz (sb-simd-sse:f32.4- (sb-simd-sse:f32.4-aref gz f) z4))
                                (d2 (sb-simd-sse:f32.4+ (sb-simd-sse:f32.4+ (sb-simd-sse:f32.4* dx dx)
                                                                            (sb-simd-sse:f32.4* dy dy))
                                                        (sb-simd-sse:f32.4* dz dz)))
                                (left (- end f))
                                (mask (logand (sb-simd-sse:f32.4-movemask (sb-simd-sse:f32.4- d2 r4))
                                              (if (>= left 4) 15 (1- (ash 1 left)))))
                                (lanes (* 4 mask)))
                           (declare (type (integer 0 15) mask) (type index left))
                           (setf (aref near found) (+ f (aref compress lanes))
                                 (aref near (+ found 1)) (+ f (aref compress (+ lanes 1)))
                                 (aref near (+ found 2)) (+ f (aref compress (+ lanes 2)))
                                 (aref near (+ found 3)) (+ f (aref compress (+ lanes 3))))
                           (incf found (logcount mask)))))
              (loop for f of-type index from start below end
                    do (when (= (aref keys f) key)
                         (setf (aref near found) f)
                         (incf found (within f))))))))
    found))
;; The block world is the static tree; bodies need a hash grid:5 ends here

;; [[file:../physics.org::#W0RLD7][The world holds every buffer and its own parameters:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +physics-features+
    '(:terrain :body-contacts :boxes :friction :rolling-resistance :restitution :sleep :mortal
      :hit-events :contact-events :expiry-events :sleep-events :forces :joints :box-bodies)
    "Every feature a world may use ([[#FEAT5X]]), in the order physics-world-features lists them. #W0RLD7"))

(defconstant +solver-stride+ 8
  "Floats per body in the solver's velocity array: vx vy vz wx wy wz and two spare. #W0RLD7")

(defconstant +delta-stride+ +solver-stride+
  "Floats per body in the solver's delta array: dx dy dz and five spare. It is the velocity
array's stride by definition, because a wide kernel gathers deltas with the velocities' row
addresses. #W0RLD7")

(defconstant +solver-origin+ 4
  "Floats before the first row of a solver array, so that on an array whose data begin 16 bytes
past a 64-byte boundary every 32-byte row starts on a 32-byte boundary. #W0RLD7")

(declaim (inline solver-row delta-row))
(defun solver-row (row)
  "Where solver row ROW begins in the velocity array. #W0RLD7"
  (declare (type index row))
  (the index (+ +solver-origin+ (* row +solver-stride+))))

(defun delta-row (row)
  "Where solver row ROW begins in the delta array. #W0RLD7"
  (declare (type index row))
  (the index (+ +solver-origin+ (* row +delta-stride+))))

(defclass kernel-family () ()
  (:documentation "A way of running the solver phases; the world holds one and every phase
dispatches on it once per call. #W0RLD7"))

(defclass scalar-kernels (kernel-family) ()
  (:documentation "The reference family: one constraint at a time, in buffer order. #W0RLD7"))

(defstruct (step-statistics (:constructor make-step-statistics ()))
  "What a world's last step measured, each figure in a slot of its own (Box2D's b2Profile):
the contacts it solved, the colours they took, its wall-clock seconds, and its error, the
deepest overlap left and the fastest approach of an overlapping contact. #W0RLD7"
  (contacts 0 :type fixnum)
  (colors 0 :type fixnum)
  (real-seconds 0d0 :type double-float)
  (max-penetration 0d0 :type double-float)
  (max-approach 0d0 :type double-float))

(defun copy-step-statistics-into (from to)
  "Copy every figure of the step-statistics FROM into TO, consing nothing, and return TO. #W0RLD7"
  (declare (type step-statistics from to))
  (setf (step-statistics-contacts to) (step-statistics-contacts from)
        (step-statistics-colors to) (step-statistics-colors from)
        (step-statistics-real-seconds to) (step-statistics-real-seconds from)
        (step-statistics-max-penetration to) (step-statistics-max-penetration from)
        (step-statistics-max-approach to) (step-statistics-max-approach from))
  to)
;; The world holds every buffer and its own parameters:1 ends here

;; [[file:../physics.org::#W0RLD7][The world holds every buffer and its own parameters:2]]
(defclass world-stores ()
  ((terrain :initarg :terrain :initform nil :accessor physics-world-terrain)
   (probe :initform (make-terrain-probe) :reader physics-world-probe)
   (kernels :initarg :kernels :accessor physics-world-kernels))
  (:documentation "What the world is made of: the terrain its bodies meet, the probe that reads
its cells, and the kernel family that runs its solver phases. #W0RLD7"))

(defclass world-bodies ()
  ((awake :initform (make-body-columns :spare 1) :reader physics-world-awake)
   (awake-scratch :initform (make-body-columns :spare 1) :reader physics-world-awake-scratch)
   (row-places :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-row-places)
   (sleeping :initform (make-body-columns) :reader physics-world-sleeping)
   (ids :initform (make-handle-table) :reader physics-world-ids))
  (:documentation "The bodies: the awake and the sleeping buffers, the awake buffer's scratch
twin and the table from handles to rows. #W0RLD7"))

(defclass world-contacts ()
  ((contacts :initform (make-contact-columns) :reader physics-world-contacts)
   (contact-table :initform (make-contact-table) :reader physics-world-contact-table)
   (contact-scratch :initform (make-contact-columns) :reader physics-world-contact-scratch)
   ;; what its snapshots and restores reuse, made at the first ([[#SNSCRT]])
   (snapshot-scratch :initform nil :accessor physics-world-snapshot-scratch)
   (constraints :initarg :constraints :initform (make-constraint-columns) :reader physics-world-constraints))
  (:documentation "The persistent contacts, their table by pair and their scratch twin, the
snapshots' scratch, and the constraints a step builds from them. #W0RLD7"))

(defclass world-events-and-boxes ()
  ((events :initform (make-event-columns) :reader physics-world-events)
   (event-data :initform (make-array 16 :initial-element nil) :accessor physics-world-event-data)
   (boxes :initform (make-box-columns) :reader physics-world-boxes)
   (box-owners :initform (make-array 16 :initial-element nil) :accessor physics-world-box-owners)
   (box-ids :initform (make-hash-table :test 'eq) :reader physics-world-box-ids)
   ;; whether any body or box has a category or mask of its own ([[#F1LT3R]]), and the lasting
   ;; sensor boxes ([[#S3NS0R]])
   (filtering :initform nil :accessor physics-world-filtering)
   (sensors :initform nil :accessor physics-world-sensors)
   (sensor-counter :initform 0 :type fixnum :accessor physics-world-sensor-counter))
  (:documentation "The step's events and the boxes posted into it, with their owners and
handles, and the filters and lasting sensors. #W0RLD7"))

(defclass world-solver-scratch ()
  ((velocities :initform (make-array 0 :element-type 'single-float) :accessor physics-world-velocities)
   (deltas :initform (make-array 0 :element-type 'single-float) :accessor physics-world-deltas)
   (color-starts :initform (make-array (+ +physics-max-colors+ 2) :element-type 'fixnum :initial-element 0)
                 :reader physics-world-color-starts)
   (color-masks :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-color-masks)
   (braced :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-braced)
   (held :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-held)
   (box-rows :initform (make-array 16 :element-type 'fixnum :initial-element 0) :accessor physics-world-box-rows)
   (box-caps :initform (make-array 16 :element-type 'single-float :initial-element 0.0)
             :accessor physics-world-box-caps)
   (held-out-count :initform 0 :type fixnum :accessor physics-world-held-out-count)
   (squeezed :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-squeezed)
   (near-cells :initform (make-array 0 :element-type 'single-float) :accessor physics-world-near-cells)
   (near-cells-step :initform -1 :type fixnum :accessor physics-world-near-cells-step)
   (buried-count :initform 0 :type fixnum :accessor physics-world-buried-count)
   (box-touch-step :initform -1 :type fixnum :accessor physics-world-box-touch-step)
   (held-rows :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-held-rows)
   ;; the finalize phase's list of the rows that leave the awake set, each row and its fate
   (departures :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-departures)
   (braced-step :initform -1 :type fixnum :accessor physics-world-braced-step)
   (column-watch :initform nil :accessor physics-world-column-watch)
   (contact-colors :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-contact-colors)
   (contact-rows :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-contact-rows)
   ;; the colouring's list of the contacts across two of its pieces ([[#SSMPYW]])
   (contact-crosses :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-contact-crosses)
   ;; the prune's list of the contact rows not seen this step ([[#PRUN3D]])
   (contact-drops :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-contact-drops)
   ;; each colouring piece's count of each colour, and its next place in each colour's run
   (colour-counts :initform (make-array 100 :element-type 'fixnum :initial-element 0)
                  :reader physics-world-colour-counts)
   (colour-places :initform (make-array 100 :element-type 'fixnum :initial-element 0)
                  :reader physics-world-colour-places))
  (:documentation "The arrays each step reuses to solve: the solver's rows of motion, the
colours, and what the boxes and the cells brace, hold and squeeze. #W0RLD7"))

(defclass world-grids ()
  ((awake-grid :initform (make-hash-grid) :reader physics-world-awake-grid)
   (awake-grid-step :initform -1 :type fixnum :accessor physics-world-awake-grid-step)
   (sleeping-grid :initform (make-hash-grid) :reader physics-world-sleeping-grid)
   (sleeping-grid-dirty :initform t :accessor physics-world-sleeping-grid-dirty)
   (fresh-grid :initform (make-hash-grid) :reader physics-world-fresh-grid)
   (newest-grid :initform (make-hash-grid) :reader physics-world-newest-grid)
   (newest-handles :initform (make-array 64 :element-type 'fixnum :initial-element 0)
                   :accessor physics-world-newest-handles)
   (newest-count :initform 0 :type fixnum :accessor physics-world-newest-count)
   (sleepers-found :initform (make-array 64 :element-type 'fixnum :initial-element 0)
                   :accessor physics-world-sleepers-found)
   (sleeping-grid-work :initform 0 :type fixnum :accessor physics-world-sleeping-grid-work)
   (fresh-handles :initform (make-array 64 :element-type 'fixnum :initial-element 0)
                  :accessor physics-world-fresh-handles)
   (fresh-count :initform 0 :type fixnum :accessor physics-world-fresh-count)
   (fresh-x :initform (make-array 0 :element-type 'single-float) :accessor physics-world-fresh-x)
   (fresh-y :initform (make-array 0 :element-type 'single-float) :accessor physics-world-fresh-y)
   (fresh-z :initform (make-array 0 :element-type 'single-float) :accessor physics-world-fresh-z)
   (settled-count :initform 0 :type fixnum :accessor physics-world-settled-count)
   (settled-stale :initform 0 :type fixnum :accessor physics-world-settled-stale)
   (grid-of :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-grid-of)
   (mortal-sleepers :initform 0 :type fixnum :accessor physics-world-mortal-sleepers)
   (added :initform (make-array 16 :element-type 'fixnum :initial-element 0) :accessor physics-world-added)
   (added-count :initform 0 :type fixnum :accessor physics-world-added-count))
  (:documentation "The hash grids of the awake, the sleeping, the freshly added and the newest
bodies, and the counts that decide when each is rebuilt. #W0RLD7"))

(defclass world-forces-and-joints ()
  (;; forces and gravity scales by handle slot, made at their first use ([[#F0RC3S]])
   (pushes :initform nil :type (or null f32-column) :accessor physics-world-pushes)
   (pushed :initform nil :accessor physics-world-pushed)
   ;; the joints, made with the first ([[#J0STOR]])
   (joints :initform nil :accessor physics-world-joints)
   ;; the box bodies' extents and points ([[#BXR0WS]]), or NIL until the first box
   (box-bodies :initform nil :accessor physics-world-box-bodies)
   (scaled-count :initform 0 :type fixnum :accessor physics-world-scaled-count)
   (max-radius :initform 0.0 :type single-float :accessor physics-world-max-radius))
  (:documentation "The forces and gravity scales by handle slot, the joints, the box bodies'
extents and points, and the largest radius. #W0RLD7"))

(defclass world-parameters ()
  ((step-seconds :initarg :step-seconds :type single-float :accessor physics-world-step-seconds)
   (substeps :initarg :substeps :type fixnum :accessor physics-world-substeps)
   (gravity-x :initarg :gravity-x :type single-float :accessor physics-world-gravity-x)
   (gravity-y :initarg :gravity-y :type single-float :accessor physics-world-gravity-y)
   (gravity-z :initarg :gravity-z :type single-float :accessor physics-world-gravity-z)
   ;; the parameters, copied and checked when the world is made (checked-physics-parameters)
   (contact-hertz :initarg :contact-hertz :accessor physics-world-contact-hertz)
   (damping-ratio :initarg :contact-damping-ratio :accessor physics-world-damping-ratio)
   (push-max :initarg :contact-push-max :accessor physics-world-push-max)
   (load-stiffening :initarg :load-stiffening :accessor physics-world-load-stiffening)
   (crowded-relax-passes :initarg :crowded-relax-passes :accessor physics-world-crowded-relax-passes)
   (crowded-depth :initarg :crowded-depth :accessor physics-world-crowded-depth)
   (slop :initarg :linear-slop :accessor physics-world-slop)
   (margin :initarg :speculative-margin :accessor physics-world-margin)
   (pair-skin :initarg :pair-skin :accessor physics-world-pair-skin)
   (pair-list :initform (make-pair-list) :reader physics-world-pair-list)
   (restitution-threshold :initarg :restitution-threshold :accessor physics-world-restitution-threshold)
   (hit-speed :initarg :hit-speed :accessor physics-world-hit-speed)
   (sleep-speed :initarg :sleep-speed :accessor physics-world-sleep-speed)
   (time-to-sleep :initarg :time-to-sleep :accessor physics-world-time-to-sleep)
   (wake-speed :initarg :wake-speed :accessor physics-world-wake-speed)
   (brace-mass-ratio :initarg :brace-mass-ratio :accessor physics-world-brace-mass-ratio)
   (reach-limit :initarg :reach-limit :accessor physics-world-reach-limit)
   (max-speed :initarg :max-speed :accessor physics-world-max-speed)
   (body-budget :initarg :body-budget :accessor physics-world-body-budget))
  (:documentation "The step's time, its gravity and the parameters of contacts, sleep and
limits, copied and checked when the world is made (checked-physics-parameters). #W0RLD7"))

(defclass world-undo ()
  ((undo-open :initform nil :accessor physics-world-undo-open)
   (undo-step-count :initform 0 :type fixnum :accessor physics-world-undo-step-count)
   (undo-woken :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-undo-woken)
   (undo-woken-count :initform 0 :type fixnum :accessor physics-world-undo-woken-count)
   (undo-sorted :initform nil :accessor physics-world-undo-sorted)
   (undo-rows :initform (make-array 0 :element-type 'fixnum) :accessor physics-world-undo-rows)
   (undo-statistics :initform (make-step-statistics) :reader physics-world-undo-statistics))
  (:documentation "What a step that fails before storing its impulses undoes (roll-back-step).
#W0RLD7"))

(defclass world-step-state ()
  ((sleep-enabled :initarg :sleep-enabled :initform t :reader physics-world-sleep-enabled)
   ;; what the world may use ([[#FEAT5X][features]]), and the step built for it
   (features :initarg :features :initform +physics-features+ :reader world-features)
   (event-mask :initarg :event-mask :initform -1 :type fixnum :reader world-event-mask)
   (phases :initform nil :accessor world-phases-built)
   (phases-source :initform nil :accessor world-phases-source)
   (kernel-variant :initform nil :accessor world-kernel-variant-built)
   (current-dt :initform (/ 1.0 60) :type single-float :accessor physics-world-current-dt)
   (current-h :initform (/ 1.0 240) :type single-float :accessor physics-world-current-h)
   (step-count :initform 0 :type fixnum :accessor physics-world-step-count)
   (stepping :initform nil :accessor physics-world-stepping)
   (rows-version :initform 0 :type fixnum :accessor physics-world-rows-version)
   (query-view :initform nil :accessor physics-world-query-view)
   (event-handler :initform nil :accessor physics-world-event-handler)
   (step-hook :initform nil :accessor physics-world-step-hook)
   (phase-clock :initform nil :accessor physics-world-phase-clock)
   ;; the world's workers ([[#W0RKP1]]), or NIL for one
   (pool :initform nil :accessor physics-world-pool)
   (statistics :initform (make-step-statistics) :reader physics-world-statistics))
  (:documentation "What the world may use and the step built for it, the step's clock and count,
the callbacks and what the last step measured. #W0RLD7"))

 ;; CLOS lays out the slots of the last superclass first: the groups are named last to first, so a
 ;; world keeps its slots in the order they are written above.
(defclass physics-world (world-step-state world-undo world-parameters world-forces-and-joints world-grids
                         world-solver-scratch world-events-and-boxes world-contacts world-bodies
                         world-stores)
  ()
  (:documentation "A simulated world of spheres over a voxel terrain: the CLOS side of the seam,
holding the columnar buffers, the parameters, the events and the kernel family. #W0RLD7"))

;; the documentation of the world's public accessors, which defclass cannot give
(loop for (name text)
        in '((physics-world-event-handler
              "The function of WORLD called with each event of a step, as map-physics-events calls it,
once the step's phases have run; or NIL. Settable. #W0RLD7")
             (physics-world-step-count "The number of steps WORLD has taken. #W0RLD7")
             (physics-world-step-hook
              "The function of WORLD called with WORLD at the end of each of its steps, after the
event handler, or NIL (the default: the step then calls nothing). Settable; a recording sets it. #W0RLD7"))
      do (setf (documentation name 'function) text))

(declaim (inline world-statistics))
(defun world-statistics (world)
  "WORLD's step-statistics, typed as such, so the step writes its slots unboxed. #W0RLD7"
  (the step-statistics (physics-world-statistics world)))

(defmacro with-world-parameters ((&rest specs) world &body body)
  "Run BODY with each of SPECS bound to a parameter of WORLD as a single-float, read once before
BODY: a spec NAME binds NAME to (physics-world-NAME WORLD), a spec (VARIABLE NAME) binds VARIABLE
to it, in the shape of with-body-columns. A featured kernel's variant may leave one unread, so
each is ignorable. #W0RLD7"
  (let ((w (gensym "WORLD"))
        (pairs (mapcar (lambda (spec) (if (consp spec) spec (list spec spec))) specs)))
    `(let* ((,w ,world)
            ,@(loop for (variable name) in pairs
                    collect `(,variable (f32 (,(intern (format nil "PHYSICS-WORLD-~A" name)) ,w)))))
       (declare (type single-float ,@(mapcar #'first pairs)) (ignorable ,w ,@(mapcar #'first pairs)))
       ,@body)))
;; The world holds every buffer and its own parameters:2 ends here

;; [[file:../physics.org::#R9M4PV][Choose the phase once: kernel families:1]]
(defvar *kernel-families* '((:scalar scalar-kernels))
  "Kernel families by name: (NAME CLASS &optional INSTRUCTION-SET), narrowest first. #R9M4PV")

(defun kernel-family-available-p (entry)
  "True when the family ENTRY needs no instruction set, or sb-simd knows the one it needs and
this processor and image run it. #R9M4PV"
  (let ((set (third entry)))
    (or (null set)
        (let ((known (sb-simd-internals:find-instruction-set set nil)))
          (and known (sb-simd-internals:instruction-set-available-p known) t)))))

(defun runnable-kernel-families ()
  "The entries of *kernel-families* whose instruction sets this CPU runs, narrowest first. #R9M4PV"
  (remove-if-not #'kernel-family-available-p *kernel-families*))

(defun available-kernel-families ()
  "The names of the registered kernel families this machine can run, narrowest first: :SCALAR,
then each wide family whose instruction set sb-simd finds present. #R9M4PV"
  (mapcar #'first (runnable-kernel-families)))

(defun register-kernel-family (name class &optional instruction-set)
  "Make the kernel family NAME, an instance of CLASS needing INSTRUCTION-SET, available to
make-physics-world, replacing an earlier entry of that NAME; families register narrowest
first, so :auto takes the last one the CPU runs. #R9M4PV"
  (unless (and (keywordp name) (not (eq name :auto)))
    (error 'invalid-physics-parameter :name :name :value name :expected "a keyword other than :auto"))
  (unless (and (symbolp class) (find-class class nil) (subtypep class 'kernel-family))
    (error 'invalid-physics-parameter :name :class :value class :expected "the name of a subclass of kernel-family"))
  (unless (or (null instruction-set) (keywordp instruction-set))
    (error 'invalid-physics-parameter :name :instruction-set :value instruction-set
                                      :expected "NIL or an sb-simd instruction set's keyword"))
  (setf *kernel-families*
        (append (remove name *kernel-families* :key #'first)
                (list (if instruction-set (list name class instruction-set) (list name class)))))
  name)

(defun make-kernel-family (name)
  "The kernel family NAME (:scalar, a wide one, or :auto for the widest this CPU runs). #R9M4PV"
  (if (eq name :auto)
      ;; sb-simd names the widest instruction set this CPU runs; its family, when registered
      (let ((widest (sb-simd:instruction-set-case (:avx2 :avx2) (:sse4.1 :sse) (:x86-64 :scalar)))
            (available (runnable-kernel-families)))
        (make-instance (second (or (assoc widest available) (car (last available))))))
      (let ((entry (assoc name *kernel-families*)))
        (unless (and entry (kernel-family-available-p entry))
          (error 'invalid-physics-parameter
                 :name :kernels :value name
                 :expected (format nil "one of ~{~S~^, ~} or :auto on this CPU"
                                   (available-kernel-families))))
        (make-instance (second entry)))))
;; Choose the phase once: kernel families:1 ends here

;; [[file:../physics.org::#M4K3WD][Making a world and adding bodies:1]]
(defun check-count (name value high)
  "VALUE, an integer from 1 to HIGH, or an invalid-physics-parameter error naming NAME. #M4K3WD"
  (unless (and (integerp value) (<= 1 value high))
    (error 'invalid-physics-parameter :name name :value value
                                      :expected (format nil "an integer from 1 to ~D" high)))
  value)

(defun check-function (world name function)
  "FUNCTION, a function or the name of one, or an invalid-physics-parameter error naming NAME. #M4K3WD"
  (unless (or (functionp function) (and (symbolp function) function (fboundp function)))
    (error 'invalid-physics-parameter :world world :name name :value function
                                      :expected "a function, or the name of a function"))
  function)

(defun make-physics-world (&key terrain (step-seconds 1/60) (substeps 4) (gravity '(0 -9.81 0))
                                (kernels :scalar) (sleep t) (features +physics-features+) (workers 1))
  "A new empty world over TERRAIN (a voxel-terrain or NIL), stepping STEP-SECONDS in SUBSTEPS
substeps under GRAVITY (a list of three numbers), solving with the kernel family KERNELS, using
only FEATURES (a list of keywords of +physics-features+, or :events for every kind of event;
every feature by default), its step shared by WORKERS threads (a count, or :auto for the
machine's cores: [[#W0RKP1]]). #M4K3WD"
  (unless (or (null terrain) (typep terrain 'voxel-terrain))
    (error 'invalid-physics-parameter :name :terrain :value terrain :expected "a voxel-terrain or NIL"))
  (let ((dt (finite-f32 :step-seconds step-seconds)))
    (unless (and (<= +physics-min-step-seconds+ dt) (< dt 1.0))
      (error 'invalid-physics-parameter :name :step-seconds :value step-seconds
                                        :expected (format nil "from ~A to under 1 second" +physics-min-step-seconds+)))
    (check-count :substeps substeps 64)
    (unless (and (listp gravity) (= (length gravity) 3))
      (error 'invalid-physics-parameter :name :gravity :value gravity :expected "a list of three numbers"))
    (let ((g (mapcar (lambda (v) (ranged-f32 :gravity v (- +physics-max-gravity+) +physics-max-gravity+))
                     gravity))
          (parameters (checked-physics-parameters)))
      (let ((features (checked-physics-features features sleep))
            (workers (checked-worker-count workers)))
        (when (and terrain (not (member :terrain features)))
          (error 'physics-feature-omitted :feature :terrain :operation 'make-physics-world))
        (open-world-workers
         (apply #'make-instance 'physics-world
               :terrain terrain :step-seconds dt :substeps substeps
               :gravity-x (first g) :gravity-y (second g) :gravity-z (third g)
               :kernels (make-kernel-family kernels)
               :sleep-enabled (and sleep (member :sleep features) t)
               :features features :event-mask (feature-event-mask features)
               :constraints (make-constraint-columns (constraint-block-floats features)
                                                     (constraint-side-floats features))
               parameters)
         workers)))))

(defmethod (setf physics-world-event-handler) :before (handler (world physics-world))
  (unless (or (null handler) (functionp handler) (and (symbolp handler) (fboundp handler)))
    (error 'invalid-physics-parameter :world world :name :event-handler :value handler
                                      :expected "NIL, a function, or the name of a function"))
  ;; a world that records no kind of event has nothing to hand a handler
  (when (and handler (zerop (world-event-mask world)))
    (error 'physics-feature-omitted :world world :feature :events :operation 'physics-world-event-handler)))

(declaim (inline check-world))
(defun check-world (world operation)
  "Signal not-a-physics-world, naming OPERATION and its argument WORLD, unless WORLD is a
physics-world: one type test, made once per call of an exported function. #M4K3WD"
  (unless (typep world 'physics-world)
    (error 'not-a-physics-world :operation operation :name 'world :value world
                                :expected "a physics-world (from make-physics-world)")))

(defmacro refuse-non-worlds (&rest accessors)
  "Make each of ACCESSORS, exported generic functions of a world (the world last, as for a setf
accessor), signal not-a-physics-world naming itself when given something else. #M4K3WD"
  `(progn
     ,@(loop for name in accessors
             collect `(defmethod no-applicable-method ((function (eql (function ,name))) &rest arguments)
                        (error 'not-a-physics-world :operation ',name :name 'world :value (car (last arguments))
                                                    :expected "a physics-world (from make-physics-world)")))))

(refuse-non-worlds physics-world-step-count physics-world-event-handler (setf physics-world-event-handler)
                   physics-world-step-hook (setf physics-world-step-hook))

(defun check-idle (world operation)
  "Signal not-a-physics-world unless WORLD is a world, and physics-world-busy unless it is between
steps. #M4K3WD"
  (check-world world operation)
  (when (physics-world-stepping world)
    (error 'physics-world-busy :world world :operation operation)))

(defun resolve-handle (world handle)
  "The set and row of HANDLE's body, or a stale-physics-handle error. #M4K3WD"
  (let* ((table (physics-world-ids world))
         (status (handle-status table handle)))
    (when status (error 'stale-physics-handle :world world :handle handle :reason status))
    (let ((slot (handle-index handle)))
      (values (aref (handle-table-set table) slot) (aref (handle-table-local table) slot)))))

(defun set-buffer (world set)
  "The body buffer of SET in WORLD. #M4K3WD"
  (if (= set +set-awake+) (physics-world-awake world) (physics-world-sleeping world)))

(defun physics-body-alive-p (world handle)
  "True when HANDLE names a body of WORLD that has not been removed or expired. #M4K3WD"
  (check-world world 'physics-body-alive-p)
  (null (handle-status (physics-world-ids world) handle)))

(defun physics-body-awake-p (world handle)
  "True when HANDLE's body is in the awake set. #M4K3WD"
  (check-world world 'physics-body-awake-p)
  (= (resolve-handle world handle) +set-awake+))

(defmacro define-body-reader (name (&rest columns) documentation)
  "Define NAME, a function of WORLD and HANDLE returning the values of COLUMNS in the row of
HANDLE's body, in whichever set it lives; DOCUMENTATION is its docstring. #M4K3WD"
  `(defun ,name (world handle)
     ,documentation
     (check-world world ',name)
     (multiple-value-bind (set row) (resolve-handle world handle)
       (with-body-columns ,columns (set-buffer world set)
         (values ,@(loop for column in columns collect `(aref ,column row)))))))

(define-body-reader physics-body-position (x y z)
  "The centre of HANDLE's body, as three values. #M4K3WD")

(define-body-reader physics-body-velocity (vx vy vz)
  "The linear velocity of HANDLE's body, as three values. #M4K3WD")

(define-body-reader physics-body-angular-velocity (wx wy wz)
  "The angular velocity of HANDLE's body, as three values. #M4K3WD")

(define-body-reader physics-body-orientation (qw qx qy qz)
  "The orientation of HANDLE's body as a unit quaternion W X Y Z, four values. #M4K3WD")

(define-body-reader physics-body-radius (radius)
  "The radius of HANDLE's body. #M4K3WD")

(define-body-reader physics-body-kind (kind)
  "The kind number of HANDLE's body: 0, or the place of its kind in *physics-body-kinds*. #M4K3WD")

(defun physics-world-awake-count (world)
  "How many bodies of WORLD are awake. #M4K3WD"
  (check-world world 'physics-world-awake-count)
  (body-columns-length (physics-world-awake world)))

(defun physics-world-sleeping-count (world)
  "How many bodies of WORLD are asleep. #M4K3WD"
  (check-world world 'physics-world-sleeping-count)
  (body-columns-length (physics-world-sleeping world)))

(defun check-coordinate (name v &optional world)
  "V, a finite real, or an invalid-physics-parameter error naming NAME when it lies beyond
+physics-coordinate-limit+. #M4K3WD"
  (unless (< (abs v) +physics-coordinate-limit+)
    (error 'invalid-physics-parameter :world world :name name :value v
                                      :expected (format nil "of magnitude under ~D m" +physics-coordinate-limit+)))
  v)

(defun check-body-room (world operation)
  "Signal physics-budget-exceeded, naming OPERATION, unless WORLD has room for one more body
under its body budget; below the budget its handle table has a slot for it ([[#B5N8JT]]). #M4K3WD"
  (let ((count (+ (physics-world-awake-count world) (physics-world-sleeping-count world))))
    (when (>= count (physics-world-body-budget world))
      (error 'physics-budget-exceeded :world world :operation operation :resource :bodies
                                      :requested (1+ count) :budget (physics-world-body-budget world)))))

(defun max-radius-for (world)
  "The largest radius a sphere of WORLD may have, and the largest half-extent of a box:
+physics-max-radius+, two cells ([[#B1GBDY]]). #M4K3WD"
  (declare (ignore world))
  +physics-max-radius+)

(defvar *box-radius-limit* nil
  "While add-physics-box adds a box's row, the largest radius add-physics-body takes: the half
diagonal of the largest box; otherwise NIL, and the limit is max-radius-for. #M4K3WD")

(defun small-radius-for (world)
  "The largest radius of a body of WORLD whose reach (radius plus margin) stays under the reach
limit, a cell: such a body gathers its cells as a 3x3x3 mask ([[#MYWGTH]]), a larger one cell by
cell ([[#B1GBDY]]). #M4K3WD"
  (- (physics-world-reach-limit world) (physics-world-margin world)))

(defun checked-material (world operation restitution friction rolling-resistance)
  "RESTITUTION, FRICTION and ROLLING-RESISTANCE, each a real or NIL for not given, as three
single-floats or NILs, once each given value is finite and in its range (restitution in [0, 1],
the others from 0 to +physics-max-friction+) and WORLD has the feature a value above zero needs;
else the error, naming OPERATION where a feature is missing. #M4K3WD"
  (flet ((one (name value high feature)
           (when value
             (let ((f (finite-f32 name value world)))
               (unless (<= 0 f high)
                 (error 'invalid-physics-parameter :world world :name name :value value
                                                   :expected (if (eq name :restitution)
                                                                 "in [0, 1]"
                                                                 (format nil "from 0 to ~A" high))))
               (when (> f 0) (require-physics-feature world feature operation))
               f))))
    (values (one :restitution restitution 1.0 :restitution)
            (one :friction friction +physics-max-friction+ :friction)
            (one :rolling-resistance rolling-resistance +physics-max-friction+ :rolling-resistance))))

(defun check-centre-in-air (world operation x y z inside-cells)
  "Signal physics-body-in-solid-cell, naming OPERATION, when the centre X Y Z lies in a solid or
non-resident cell of WORLD's terrain, unless INSIDE-CELLS is :push-out; signal
invalid-physics-parameter when INSIDE-CELLS is neither that nor :refuse. #M4K3WD"
  (unless (member inside-cells '(:refuse :push-out))
    (error 'invalid-physics-parameter :world world :name :inside-cells :value inside-cells
                                      :expected ":refuse or :push-out"))
  (let ((terrain (physics-world-terrain world)))
    (when (and terrain (eq inside-cells :refuse))
      ;; the coordinates are checked finite and within the limit: their cells are cells
      (let* ((ix (cell-floor x)) (iy (cell-floor y)) (iz (cell-floor z))
             (chunk (gethash (chunk-key ix iy iz) (voxel-terrain-chunks terrain))))
        (when (or (null chunk) (plusp (aref (the chunk-storage chunk) (cell-offset ix iy iz))))
          (error 'physics-body-in-solid-cell :world world :operation operation :name :position
                                             :value (list x y z) :cell (list ix iy iz)
                                             :resident (terrain-resident-p terrain ix iy iz)
                                             :expected "a centre in an air cell of the resident terrain"))))))

(defun add-physics-body (world x y z &key (radius 0.25) (mass 1.0) (restitution 0.0) (friction 0.6)
                                       (rolling-resistance 0.0) (vx 0.0) (vy 0.0) (vz 0.0)
                                       life (collide-with-bodies t) report-hits (kind 0)
                                       (inside-cells :refuse) (category +default-category+)
                                       (mask +all-categories+) (gravity-scale 1.0))
  "Add an awake sphere centred at X Y Z to WORLD and return its handle. LIFE, when given, is the
number of seconds after which it expires. A centre in a solid or non-resident cell is refused
with physics-body-in-solid-cell, unless INSIDE-CELLS is :push-out: then the body is added and its
cell's contact pushes it out through the shallowest face whose neighbour is air ([[#MYWH16]]).
CATEGORY and MASK, sets of sixteen bits, choose the bodies and boxes it meets ([[#F1LT3R]]).
GRAVITY-SCALE multiplies the world's gravity for this body alone ([[#F0RC3S]]). #M4K3WD"
  (check-idle world 'add-physics-body)
  (let* ((x (finite-f32 :x x world)) (y (finite-f32 :y y world)) (z (finite-f32 :z z world))
         (r (finite-f32 :radius radius world)) (m (finite-f32 :mass mass world))
         (vx (finite-f32 :vx vx world)) (vy (finite-f32 :vy vy world)) (vz (finite-f32 :vz vz world))
         (mortal (and life t))
         (life (if life (finite-f32 :life life world) 0.0))
         (limit (or *box-radius-limit* (max-radius-for world))))
    (check-coordinate :x x world) (check-coordinate :y y world) (check-coordinate :z z world)
    (check-centre-in-air world 'add-physics-body x y z inside-cells)
    (unless (<= +physics-min-radius+ r limit)
      (error 'invalid-physics-radius :world world :value radius :limit limit))
    (unless (<= +physics-min-mass+ m +physics-max-mass+)
      (error 'invalid-physics-parameter :world world :name :mass :value mass
                                        :expected (format nil "from ~A to ~A kg" +physics-min-mass+ +physics-max-mass+)))
    (check-velocity vx vy vz (physics-world-max-speed world) world)
    (when (and mortal (<= life 0))
      (error 'invalid-physics-parameter :world world :name :life :value life :expected "> 0 seconds, or NIL"))
    (unless (typep kind 'fixnum) (error 'invalid-physics-parameter :world world :name :kind :value kind :expected "a fixnum"))
    (setf gravity-scale (checked-gravity-scale world 'add-physics-body gravity-scale))
    (let ((filter (checked-filter world category mask)))
    ;; a body that needs a feature the world left out is refused, not quietly given less
    (multiple-value-bind (e mu rho)
        (checked-material world 'add-physics-body (finite-f32 :restitution restitution world)
                          (finite-f32 :friction friction world)
                          (finite-f32 :rolling-resistance rolling-resistance world))
    (flet ((needs (feature) (require-physics-feature world feature 'add-physics-body)))
      (when (> life 0) (needs :mortal))
      (when collide-with-bodies (needs :body-contacts))
      (when report-hits (needs :hit-events)))
    (check-body-room world 'add-physics-body)
    (let* ((awake (physics-world-awake world))
           (row (body-columns-append awake))
           (handle (handle-table-allocate (physics-world-ids world) +set-awake+ row)))
      (incf (physics-world-rows-version world))
      (with-body-columns ((bx x) (by y) (bz z) (bvx vx) (bvy vy) (bvz vz) qw (radius-c radius)
                          inverse-mass inverse-inertia (restitution-c restitution) (friction-c friction)
                          (rolling-resistance-c rolling-resistance) (life-c life) flags
                          (handle-c handle) (kind-c kind))
          awake
        (setf (aref bx row) x (aref by row) y (aref bz row) z
              (aref bvx row) vx (aref bvy row) vy (aref bvz row) vz
              (aref qw row) 1.0
              (aref radius-c row) r (aref inverse-mass row) (/ 1.0 m)
              (aref inverse-inertia row) (/ 5.0 (* 2.0 m r r))
              (aref restitution-c row) e (aref friction-c row) mu (aref rolling-resistance-c row) rho
              (aref life-c row) life
              (aref flags row) (logior (if report-hits +flag-report-hits+ 0)
                                       (if collide-with-bodies 0 +flag-terrain-only+)
                                       (ash filter +flag-filter-shift+))
              (aref handle-c row) handle (aref kind-c row) kind))
      (setf (physics-world-max-radius world) (max (physics-world-max-radius world) r))
      (note-filter world filter)
      (note-gravity-scale world handle gravity-scale)
      (note-added-body world handle)
      handle)))))
;; Making a world and adding bodies:1 ends here

;; [[file:../physics.org::#E7V3NT][Events are rows too:1]]
(define-physics-layout event-columns
  "What happened during the last step, one row per event. #E7V3NT"
  (kind fixnum) (handle-a fixnum) (handle-b fixnum)
  (x single-float) (y single-float) (z single-float) (speed single-float))

(defun push-event (world kind handle-a handle-b x y z speed &optional datum)
  "Record an event of KIND (a fixnum code) in WORLD's event buffer, when WORLD records events of
that kind ([[#FEAT5X][its features]]). #E7V3NT"
  (declare (type fixnum kind handle-a handle-b) (type single-float x y z speed))
  (when (logbitp kind (the fixnum (world-event-mask world)))
  (let* ((events (physics-world-events world))
         (row (event-columns-append events)))
    (with-event-columns ((k kind) (a handle-a) (b handle-b) (ex x) (ey y) (ez z) (s speed)) events
      (setf (aref k row) kind (aref a row) handle-a (aref b row) handle-b
            (aref ex row) x (aref ey row) y (aref ez row) z (aref s row) speed))
    (when datum
      (let ((data (physics-world-event-data world)))
        (when (>= row (length data))
          (setf data (replace (make-array (* 2 (1+ row)) :initial-element nil) data)
                (physics-world-event-data world) data))
        (setf (svref data row) datum)))
    row)))

(defconstant +event-begin+ 0 "Event code of :begin. #E7V3NT")

(defconstant +event-end+ 1 "Event code of :end. #E7V3NT")

(defconstant +event-hit+ 2 "Event code of :hit. #E7V3NT")

(defconstant +event-slept+ 3 "Event code of :slept. #E7V3NT")

(defconstant +event-woke+ 4 "Event code of :woke. #E7V3NT")

(defconstant +event-expired+ 5 "Event code of :expired. #E7V3NT")

(defconstant +event-escaped+ 6 "Event code of :escaped. #E7V3NT")

(defconstant +event-held-out+ 7 "Event code of :held-out. #E7V3NT")

(defparameter +event-kinds+ #(:begin :end :hit :slept :woke :expired :escaped :held-out
                               :sensor-enter :sensor-leave :joint-break :joint-removed)
  "Event kind keywords by code. #E7V3NT")

(defun map-physics-events (function world)
  "Call FUNCTION on each event of WORLD's last step with the kind (:begin :end :hit :slept
:woke :expired :escaped :held-out :sensor-enter :sensor-leave), the two handles (the second -1 when none), the point X Y Z, the approach
speed, and the datum (a box's owner, or NIL). #E7V3NT"
  (check-world world 'map-physics-events)
  (check-function world :function function)
  (let ((events (physics-world-events world)) (data (physics-world-event-data world)))
    (with-event-columns (kind handle-a handle-b x y z speed) events
      (dotimes (i (event-columns-length events))
        (funcall function (svref +event-kinds+ (aref kind i)) (aref handle-a i) (aref handle-b i)
                 (aref x i) (aref y i) (aref z i) (aref speed i)
                 (and (< i (length data)) (svref data i)))))
    (values)))
;; Events are rows too:1 ends here

;; [[file:../physics.org::#QKS4GZ][Sleep is relocation; boxes, throws and edits wake:1]]
(defconstant +woken-sleep-credit+ 0.5
  "The part of the time to sleep a woken body starts with already counted. #QKS4GZ")

(defun relocate-body (world from-set row to-set)
  "Move the body at ROW of FROM-SET to the end of TO-SET, patching the forwarding address of
the body and of the row that fills its hole. Return the body's new row. #QKS4GZ"
  (let* ((ids (physics-world-ids world))
         (from (set-buffer world from-set))
         (to (set-buffer world to-set))
         (handle (aref (body-columns-handle from) row))
         (new-row (body-columns-append to)))
    (incf (physics-world-rows-version world))
    (body-columns-copy-row from row to new-row)
    (let ((moved (body-columns-swap-remove from row)))
      (setf (aref (handle-table-set ids) (handle-index handle)) to-set
            (aref (handle-table-local ids) (handle-index handle)) new-row)
      (when (>= moved 0)
        (setf (aref (handle-table-local ids) (handle-index (aref (body-columns-handle from) row))) row)))
    new-row))

(defun sleep-physics-body (world row)
  "Put the awake body at ROW to sleep: relocate it, zero its motion, note :slept. #QKS4GZ"
  (let* ((handle (aref (body-columns-handle (physics-world-awake world)) row))
         (new (relocate-body world +set-awake+ row +set-sleeping+))
         (s (physics-world-sleeping world)))
    (with-body-columns (vx vy vz wx wy wz sleep-time life flags) s
      (setf (aref vx new) 0.0 (aref vy new) 0.0 (aref vz new) 0.0
            (aref wx new) 0.0 (aref wy new) 0.0 (aref wz new) 0.0 (aref sleep-time new) 0.0
            ;; bracing starts afresh when it wakes
            (aref flags new) (logandc2 (aref flags new) (logior +flag-braced+ +flag-column-steps+)))
      (when (> (aref life new) 0.0) (incf (physics-world-mortal-sleepers world))))
    (note-fresh-sleeper world handle)
    (push-event world +event-slept+ handle +no-body+ 0.0 0.0 0.0 0.0)
    new))

(defun wake-physics-body (world row)
  "Wake the sleeping body at ROW: relocate it to the end of the awake set, its stillness counted
from +woken-sleep-credit+ of the time to sleep, and note :woke. In a step, note ROW in the step's
undo log too (roll-back-step). #QKS4GZ"
  (when (physics-world-undo-open world)
    (let ((log (physics-world-undo-woken world)) (k (physics-world-undo-woken-count world)))
      (setf log (fixnum-room log (1+ k) :least 16) (physics-world-undo-woken world) log)
      (setf (aref log k) row (physics-world-undo-woken-count world) (1+ k))))
  (let* ((handle (aref (body-columns-handle (physics-world-sleeping world)) row))
         (new (progn (when (> (aref (body-columns-life (physics-world-sleeping world)) row) 0.0)
                       (decf (physics-world-mortal-sleepers world)))
                     (relocate-body world +set-sleeping+ row +set-awake+))))
    ;; a sleeper was still for the whole time to sleep: it wakes with half of it counted
    (setf (aref (body-columns-sleep-time (physics-world-awake world)) new)
          (* +woken-sleep-credit+ (f32 (physics-world-time-to-sleep world))))
    (leave-sleeping-grids world handle)
    (push-event world +event-woke+ handle +no-body+ 0.0 0.0 0.0 0.0)
    new))

(defun wake-handle (world handle)
  "Wake HANDLE's body if it sleeps; return its awake row. #QKS4GZ"
  (multiple-value-bind (set row) (resolve-handle world handle)
    (if (= set +set-awake+) row (wake-physics-body world row))))

(defun %remove-body (world set row)
  "Remove the body at ROW of SET and free its handle; its contacts are pruned next step. #QKS4GZ"
  (let* ((ids (physics-world-ids world))
         (buffer (set-buffer world set))
         (handle (aref (body-columns-handle buffer) row))
         (moved (progn ;; its joints go first, while its row is its own ([[#J0STOR]])
                       (when (physics-world-joints world) (remove-body-joints world handle))
                       (when (physics-world-box-bodies world) (forget-box world handle))
                       (when (and (= set +set-sleeping+) (> (aref (body-columns-life buffer) row) 0.0))
                         (decf (physics-world-mortal-sleepers world)))
                       (when (= set +set-sleeping+) (leave-sleeping-grids world handle))
                       (body-columns-swap-remove buffer row))))
    (incf (physics-world-rows-version world))
    (when (>= moved 0)
      (setf (aref (handle-table-local ids) (handle-index (aref (body-columns-handle buffer) row))) row))
    (when (physics-world-pushes world) (forget-pushes world handle))
    (handle-table-release ids handle)
    handle))

(defun trim-physics-world (world)
  "Give back the room WORLD's buffers grew to beyond what they hold: the awake buffer and its
sorting scratch keep room for twice the awake rows, the sleeping buffer and the sleeping grids
for what they hold, the events and the lists for their rows, and the solver's arrays are let go,
to grow again as the next steps need. Call it between steps, off the hot path, after a pile has
fallen asleep or been removed. Return WORLD. #QKS4GZ"
  (check-idle world 'trim-physics-world)
  (let* ((awake (physics-world-awake world))
         (n (body-columns-length awake)))
    (ensure-sleeping-grid world)
    (body-columns-trim awake (* 2 n))
    (body-columns-trim (physics-world-awake-scratch world) (body-columns-capacity awake))
    (body-columns-trim (physics-world-sleeping world) 0)
    ;; the events of the last step stay readable: trimming keeps every row
    (event-columns-trim (physics-world-events world) 0)
    (let ((count (physics-world-added-count world)))
      (setf (physics-world-added world) (fixnum-column-copy (physics-world-added world) (max 16 count) count)))
    (setf (physics-world-row-places world) (make-array 0 :element-type 'fixnum)
          (physics-world-undo-rows world) (make-array 0 :element-type 'fixnum)
          (physics-world-velocities world) (make-array 0 :element-type 'single-float)
          (physics-world-deltas world) (make-array 0 :element-type 'single-float)
          (physics-world-color-masks world) (make-array 0 :element-type 'fixnum)
          (physics-world-braced world) (make-array 0 :element-type 'fixnum)
          (physics-world-held world) (make-array 0 :element-type 'fixnum)
          (physics-world-departures world) (make-array 0 :element-type 'fixnum))
    (flet ((list-room (handles count) (fixnum-column-copy handles (max 64 count) count)))
      (setf (physics-world-fresh-handles world)
            (list-room (physics-world-fresh-handles world) (physics-world-fresh-count world))
            (physics-world-newest-handles world)
            (list-room (physics-world-newest-handles world) (physics-world-newest-count world))
            (physics-world-fresh-x world) (make-array 0 :element-type 'single-float)
            (physics-world-fresh-y world) (make-array 0 :element-type 'single-float)
            (physics-world-fresh-z world) (make-array 0 :element-type 'single-float)))
    ;; the grids keep every entry, in its place: the next walks meet what they met before;
    ;; they are marked for a check, as a query view reads the mark
    (hash-grid-trim (physics-world-sleeping-grid world))
    (hash-grid-trim (physics-world-fresh-grid world))
    (hash-grid-trim (physics-world-newest-grid world))
    (setf (physics-world-sleeping-grid-dirty world) t)
    world))

(defun physics-world-bytes (world)
  "The bytes WORLD's own storage takes: every array reachable from its slots, through the
structures of columns, grids and tables, counted once, with the structures themselves; its terrain
and kernel family not. As a second value, each slot's share, largest first, as an alist. #QKS4GZ"
  (check-world world 'physics-world-bytes)
  (let ((seen (make-hash-table :test 'eq)))
    (labels ((bytes (object)
               (cond ((or (not (typep object '(or array structure-object))) (gethash object seen)) 0)
                     (t (setf (gethash object seen) t)
                        (+ (sb-ext:primitive-object-size object)
                           (typecase object
                             (simple-vector (loop for item across object sum (bytes item)))
                             (structure-object
                              (loop for slot in (sb-mop:class-slots (class-of object))
                                    sum (bytes (slot-value object (sb-mop:slot-definition-name slot)))))
                             (t 0)))))))
      (let ((shares (loop for slot in (sb-mop:class-slots (class-of world))
                          for name = (sb-mop:slot-definition-name slot)
                          unless (member name '(terrain probe kernels))
                            collect (cons name (bytes (slot-value world name))))))
        (values (reduce #'+ shares :key #'cdr) (sort shares #'> :key #'cdr))))))

(defun remove-physics-body (world handle)
  "Remove HANDLE's body from WORLD; HANDLE goes stale. #QKS4GZ"
  (check-idle world 'remove-physics-body)
  (multiple-value-bind (set row) (resolve-handle world handle)
    (%remove-body world set row)
    (values)))

(defun set-physics-body-velocity (world handle vx vy vz)
  "Set the linear velocity of HANDLE's body, waking it. #QKS4GZ"
  (check-idle world 'set-physics-body-velocity)
  (let ((vx (finite-f32 :vx vx world)) (vy (finite-f32 :vy vy world)) (vz (finite-f32 :vz vz world)))
    (resolve-handle world handle)
    (check-velocity vx vy vz (physics-world-max-speed world) world)
    (let ((row (wake-handle world handle)) (awake (physics-world-awake world)))
      (with-body-columns ((bvx vx) (bvy vy) (bvz vz) sleep-time) awake
        (setf (aref bvx row) vx (aref bvy row) vy (aref bvz row) vz (aref sleep-time row) 0.0)))
    (values)))

(defun wake-physics-bodies-near (world x y z radius)
  "Wake every sleeping body of WORLD whose surface lies within RADIUS of point X Y Z; return
how many woke. Call it after editing terrain near bodies. #QKS4GZ"
  (check-idle world 'wake-physics-bodies-near)
  (wake-sleepers-near world (check-coordinate :x (finite-f32 :x x world) world)
                      (check-coordinate :y (finite-f32 :y y world) world)
                      (check-coordinate :z (finite-f32 :z z world) world)
                      (ranged-f32 :radius radius 0 (* 2 +physics-coordinate-limit+) world)))

(defun wake-sleepers-near (world x y z radius)
  "Wake every sleeping body of WORLD whose surface lies within RADIUS of the point X Y Z, numbers
already checked; return how many woke. #QKS4GZ"
  (let ((s (physics-world-sleeping world)) (count 0))
    (loop with row = (1- (body-columns-length s))
          while (>= row 0)
          do (with-body-columns ((sx x) (sy y) (sz z) (r radius)) s
               (let ((dx (- (aref sx row) x)) (dy (- (aref sy row) y)) (dz (- (aref sz row) z))
                     (reach (+ radius (aref r row))))
                 (when (<= (+ (* dx dx) (* dy dy) (* dz dz)) (* reach reach))
                   (wake-physics-body world row)
                   (incf count))))
             (decf row))
    count))
;; Sleep is relocation; boxes, throws and edits wake:1 ends here

;; [[file:../physics.org::#T3LPRT][A body moved by hand: teleporting:1]]
(defun drop-body-contacts (world handle)
  "Drop every contact of HANDLE's body from WORLD, a touching one with the :end event pruning gives
it, and wake the sleeping body on the other side of each contact between two bodies; return how
many contacts were dropped. #T3LPRT"
  (let ((contacts (physics-world-contacts world))
        (table (physics-world-contact-table world))
        (ids (physics-world-ids world))
        (dropped 0))
    (declare (type fixnum dropped))
    (loop for row of-type fixnum from (1- (contact-columns-length contacts)) downto 0
          do (with-contact-columns (key kind handle-a handle-b touching geometry) contacts
               (let* ((a (aref handle-a row)) (b (aref handle-b row))
                      (pair (= (aref kind row) +contact-pair+)))
                 (when (or (= a handle) (and pair (= b handle)))
                   (let ((other (if (= a handle) b a)))
                     (when (and pair (null (handle-status ids other))
                                (= (aref (handle-table-set ids) (handle-index other)) +set-sleeping+))
                       (wake-handle world other)))
                   (when (= (aref touching row) 1)
                     (push-event world +event-end+ a b (contact@ geometry row px) (contact@ geometry row py)
                                 (contact@ geometry row pz) 0.0))
                   (contact-table-delete table (aref key row))
                   (let ((moved (contact-columns-swap-remove contacts row)))
                     (when (>= moved 0) (contact-table-put table (aref key row) row)))
                   (incf dropped)))))
    dropped))

(defun set-physics-body-position (world handle x y z &key (inside-cells :refuse))
  "Move the centre of HANDLE's body to X Y Z, keeping its velocity and spin, and wake it; the
sleepers within its reach where it was wake too, and its contacts are dropped. A centre in a solid
or non-resident cell is refused as add-physics-body refuses one (physics-body-in-solid-cell, unless
INSIDE-CELLS is :push-out); a refused move changes nothing. #T3LPRT"
  (check-idle world 'set-physics-body-position)
  (let ((x (finite-f32 :x x world)) (y (finite-f32 :y y world)) (z (finite-f32 :z z world)))
    (multiple-value-bind (set row) (resolve-handle world handle)
      (check-coordinate :x x world) (check-coordinate :y y world) (check-coordinate :z z world)
      (check-centre-in-air world 'set-physics-body-position x y z inside-cells)
      (let* ((buffer (set-buffer world set))
             (ox (aref (body-columns-x buffer) row)) (oy (aref (body-columns-y buffer) row))
             (oz (aref (body-columns-z buffer) row))
             (reach (+ (aref (body-columns-radius buffer) row) (f32 (physics-world-margin world)))))
        (wake-handle world handle)
        (wake-sleepers-near world ox oy oz reach)
        (drop-body-contacts world handle)
        ;; waking others appends rows: the body's row is read again
        (let ((row (nth-value 1 (resolve-handle world handle))))
          (with-body-columns ((bx x) (by y) (bz z) sleep-time flags) (physics-world-awake world)
            (setf (aref bx row) x (aref by row) y (aref bz row) z (aref sleep-time row) 0.0
                  (aref flags row) (logandc2 (aref flags row) (logior +flag-braced+ +flag-column-steps+)))))
        (incf (physics-world-rows-version world))
        (note-added-body world handle)
        (values)))))
;; A body moved by hand: teleporting:1 ends here

;; [[file:../physics.org::#1MPULS][Impulses and spin given by hand:1]]
(defun max-spin-for (world)
  "The largest angular speed, rad/s, a body of WORLD may be given: twice its top speed over the
smallest radius. #1MPULS"
  (/ (* 2.0 (f32 (physics-world-max-speed world))) +physics-min-radius+))

(defmacro check-vector-bound (world name value ax ay az limit expected)
  "Signal invalid-physics-parameter naming NAME unless the single-floats AX AY AZ make a vector no
longer than LIMIT; the forms VALUE and EXPECTED, the value refused and what was wanted, are
evaluated only then, so a call that passes conses nothing. Each component is bounded first, so no
square overflows. #1MPULS"
  (let ((x (gensym "X")) (y (gensym "Y")) (z (gensym "Z")) (l (gensym "LIMIT")))
    `(let ((,x ,ax) (,y ,ay) (,z ,az) (,l ,limit))
       (declare (type single-float ,x ,y ,z ,l))
       (unless (and (<= (abs ,x) ,l) (<= (abs ,y) ,l) (<= (abs ,z) ,l)
                    (<= (+ (* ,x ,x) (* ,y ,y) (* ,z ,z)) (* ,l ,l)))
         (error 'invalid-physics-parameter :world ,world :name ,name :value ,value :expected ,expected)))))

(defun checked-impulse (world handle jx jy jz &optional px py pz)
  "The velocity and angular velocity HANDLE's body would have after the impulse JX JY JZ at its
centre or, when PX is given, at the point PX PY PZ, as six single-floats, once every number and
both results are checked; else the error. #1MPULS"
  (let ((jx (finite-f32 :jx jx world)) (jy (finite-f32 :jy jy world)) (jz (finite-f32 :jz jz world))
        (px (and px (finite-f32 :px px world))) (py (and px (finite-f32 :py py world)))
        (pz (and px (finite-f32 :pz pz world))))
    (multiple-value-bind (set row) (resolve-handle world handle)
      (let* ((b (set-buffer world set))
             (im (aref (body-columns-inverse-mass b) row))
             (top (f32 (physics-world-max-speed world)))
             (jmax (/ (* 2.0 top) im)))
        (check-vector-bound world :impulse (list jx jy jz) jx jy jz jmax
                            (format nil "at most ~,1F N s: twice the top speed times the mass" jmax))
        (let ((vx (+ (aref (body-columns-vx b) row) (* jx im)))
              (vy (+ (aref (body-columns-vy b) row) (* jy im)))
              (vz (+ (aref (body-columns-vz b) row) (* jz im)))
              (wx (aref (body-columns-wx b) row)) (wy (aref (body-columns-wy b) row))
              (wz (aref (body-columns-wz b) row)))
          (check-vector-bound world :impulse (list jx jy jz) vx vy vz top
                              (format nil "an impulse that leaves a speed of at most ~A m/s" top))
          (when px
            (check-coordinate :px px world) (check-coordinate :py py world) (check-coordinate :pz pz world)
            (let* ((rx (- px (aref (body-columns-x b) row))) (ry (- py (aref (body-columns-y b) row)))
                   (rz (- pz (aref (body-columns-z b) row)))
                   (reach (+ (aref (body-columns-radius b) row) (f32 (physics-world-slop world))))
                   (ii (aref (body-columns-inverse-inertia b) row)))
              (unless (<= (+ (* rx rx) (* ry ry) (* rz rz)) (* reach reach))
                (error 'invalid-physics-parameter :world world :name :point :value (list px py pz)
                                                  :expected (format nil "a point of the body, within ~,4F m of its centre" reach)))
              (setf wx (+ wx (* ii (- (* ry jz) (* rz jy))))
                    wy (+ wy (* ii (- (* rz jx) (* rx jz))))
                    wz (+ wz (* ii (- (* rx jy) (* ry jx)))))
              (let ((spin (max-spin-for world)))
                (check-vector-bound world :angular-velocity (list wx wy wz) wx wy wz spin
                                    (format nil "an impulse that leaves a spin of at most ~,1F rad/s" spin)))))
          (values vx vy vz wx wy wz))))))

(defun write-body-motion (world handle vx vy vz wx wy wz)
  "Wake HANDLE's body and give it the velocity VX VY VZ and the angular velocity WX WY WZ, with none
of its time to sleep counted. #1MPULS"
  (let ((row (wake-handle world handle)))
    (with-body-columns ((bvx vx) (bvy vy) (bvz vz) (bwx wx) (bwy wy) (bwz wz) sleep-time)
        (physics-world-awake world)
      (setf (aref bvx row) vx (aref bvy row) vy (aref bvz row) vz
            (aref bwx row) wx (aref bwy row) wy (aref bwz row) wz (aref sleep-time row) 0.0)))
  (values))

(defun apply-physics-impulse (world handle jx jy jz)
  "Give HANDLE's body the impulse JX JY JZ, N s, at its centre: its velocity gains J/m. Wake the
body. A component beyond twice the top speed times the mass, or a velocity left beyond the top
speed, is refused naming :impulse, and nothing changes. #1MPULS"
  (check-idle world 'apply-physics-impulse)
  (multiple-value-call #'write-body-motion world handle
    (checked-impulse world handle jx jy jz)))

(defun apply-physics-impulse-at (world handle jx jy jz px py pz)
  "Give HANDLE's body the impulse JX JY JZ, N s, at the point PX PY PZ of the body: its velocity
gains J/m and its angular velocity I^-1 (r x J), r the point less the centre, I = 2/5 m r^2. Wake
the body. A point farther from the centre than the radius and the slop is refused naming :point,
a spin left beyond the limit naming :angular-velocity, and nothing changes. #1MPULS"
  (check-idle world 'apply-physics-impulse-at)
  (multiple-value-call #'write-body-motion world handle
    (checked-impulse world handle jx jy jz px py pz)))

(defun set-physics-body-angular-velocity (world handle wx wy wz)
  "Set the angular velocity of HANDLE's body, rad/s about the world's axes, waking it; a spin over
twice the top speed over the smallest radius is refused naming :angular-velocity. #1MPULS"
  (check-idle world 'set-physics-body-angular-velocity)
  (let ((wx (finite-f32 :wx wx world)) (wy (finite-f32 :wy wy world)) (wz (finite-f32 :wz wz world)))
    (resolve-handle world handle)
    (let ((spin (max-spin-for world)))
      (check-vector-bound world :angular-velocity (list wx wy wz) wx wy wz spin
                          (format nil "a spin of at most ~,1F rad/s" spin)))
    (multiple-value-bind (vx vy vz) (physics-body-velocity world handle)
      (write-body-motion world handle vx vy vz wx wy wz))))
;; Impulses and spin given by hand:1 ends here

;; [[file:../physics.org::#F0RC3S][Forces for the next step, and gravity by the body:1]]
(defconstant +physics-max-acceleration+ 1000000.0
  "Largest acceleration, m/s², along each axis and in length, that the forces applied to a body
for one step may give it. #F0RC3S")

(defconstant +physics-max-gravity-scale+ 100.0
  "Largest magnitude of a body's gravity scale. #F0RC3S")

(defun ensure-pushes (world)
  "WORLD's pushes, made or grown to cover every slot of its handle table: four floats a slot, the
force's x y z and the gravity scale, 0 0 0 1 for a slot none has set. #F0RC3S"
  (let ((need (* 4 (length (handle-table-set (physics-world-ids world)))))
        (old (physics-world-pushes world)))
    (if (and old (>= (length old) need))
        old
        (let ((new (make-array need :element-type 'single-float :initial-element 0.0)))
          (loop for p from 3 below need by 4 do (setf (aref new p) 1.0))
          (when old (replace new old))
          (setf (physics-world-pushes world) new)))))

(defun checked-pushes (world)
  "WORLD's pushes, once they are seen to cover every slot its handle table has opened, which the
pushed integration reads without checks; else physics-world-invalid. #F0RC3S"
  (let ((pushes (physics-world-pushes world)))
    (unless (and pushes (>= (length pushes) (* 4 (handle-table-count (physics-world-ids world)))))
      (error 'physics-world-invalid :world world :invariant "the pushes cover every handle slot"))
    pushes))

(declaim (inline pushes-live-p))
(defun pushes-live-p (world)
  "True when WORLD's next substeps have a force to apply or a gravity scale other than 1. #F0RC3S"
  (and (physics-world-pushes world)
       (or (physics-world-pushed world) (plusp (physics-world-scaled-count world)))))

(defun checked-gravity-scale (world operation scale)
  "SCALE as a single-float of magnitude at most +physics-max-gravity-scale+, given to OPERATION,
once WORLD is seen to have :forces when it is not 1; else the error. #F0RC3S"
  (let ((s (ranged-f32 :gravity-scale scale (- +physics-max-gravity-scale+) +physics-max-gravity-scale+ world)))
    (unless (= s 1.0) (require-physics-feature world :forces operation))
    s))

(defun note-gravity-scale (world handle scale)
  "Give HANDLE's slot the gravity SCALE, counting the scales that are not 1; a world that has no
pushes and is given 1 is left without. #F0RC3S"
  (when (or (physics-world-pushes world) (/= scale 1.0))
    (let* ((pushes (ensure-pushes world))
           (p (+ 3 (* 4 (handle-index handle))))
           (old (aref pushes p)))
      (incf (physics-world-scaled-count world) (- (if (= scale 1.0) 0 1) (if (= old 1.0) 0 1)))
      (setf (aref pushes p) scale)))
  (values))

(defun forget-pushes (world handle)
  "Set HANDLE's slot back to no force and a gravity scale of 1, as its body goes. #F0RC3S"
  (note-gravity-scale world handle 1.0)
  (let ((pushes (physics-world-pushes world)) (p (* 4 (handle-index handle))))
    (setf (aref pushes p) 0.0 (aref pushes (+ p 1)) 0.0 (aref pushes (+ p 2)) 0.0))
  (values))

(defun clear-physics-forces (world)
  "Spend the forces WORLD's last step applied: every slot's force back to zero. #F0RC3S"
  (let ((pushes (physics-world-pushes world)))
    (declare (type f32-column pushes))
    (loop for p of-type index from 0 below (length pushes) by 4
          do (setf (aref pushes p) 0.0 (aref pushes (+ p 1)) 0.0 (aref pushes (+ p 2)) 0.0))
    (setf (physics-world-pushed world) nil)))

(defun integrate-pushed-velocities-range (v pushes handles inverse-mass start end h gx gy gz max-speed)
  "Add to velocity rows START..END of V, over H, gravity times each body's gravity scale and its
force times its inverse mass, read from PUSHES at the slot of its handle in HANDLES, and clamp their
speed to MAX-SPEED. #F0RC3S"
  (declare (type f32-column v pushes inverse-mass) (type fixnum-column handles) (type index start end)
           (type single-float h gx gy gz max-speed) #.+kernel-policy+)
  (loop with max2 of-type single-float = (* max-speed max-speed)
        for i of-type index from start below end
        for o of-type index = (solver-row i)
        for p of-type index = (* 4 (handle-index (aref handles i)))
        do (let ((s (aref pushes (+ p 3))) (im (aref inverse-mass i)))
             (store-clamped-velocity v o
                                     (+ (aref v o) (* h (+ (* s gx) (* im (aref pushes p)))))
                                     (+ (aref v (+ o 1)) (* h (+ (* s gy) (* im (aref pushes (+ p 1))))))
                                     (+ (aref v (+ o 2)) (* h (+ (* s gz) (* im (aref pushes (+ p 2))))))
                                     max-speed max2))))

(defun apply-physics-force (world handle fx fy fz)
  "Add the force FX FY FZ, N, to what HANDLE's body is given for the next step, and wake it; the
step applies the sum in every substep, as it applies gravity, and then spends it. A sum beyond
+physics-max-acceleration+ times the mass is refused naming :force, and nothing changes. #F0RC3S"
  (check-idle world 'apply-physics-force)
  (let ((fx (finite-f32 :fx fx world)) (fy (finite-f32 :fy fy world)) (fz (finite-f32 :fz fz world)))
    (multiple-value-bind (set row) (resolve-handle world handle)
      (require-physics-feature world :forces 'apply-physics-force)
      (let* ((limit (/ +physics-max-acceleration+ (aref (body-columns-inverse-mass (set-buffer world set)) row)))
             (old (physics-world-pushes world))
             (p (* 4 (handle-index handle)))
             ;; a finite component refused below is under 3.4e38, and what it is added to under 1e11
             (sx (if old (+ fx (aref old p)) fx))
             (sy (if old (+ fy (aref old (+ p 1))) fy))
             (sz (if old (+ fz (aref old (+ p 2))) fz)))
        (check-vector-bound world :force (list fx fy fz) sx sy sz limit
                            (format nil "a force that, with those given since the last step, is at most ~,1F N" limit))
        (let ((pushes (ensure-pushes world)))
          (setf (aref pushes p) sx (aref pushes (+ p 1)) sy (aref pushes (+ p 2)) sz
                (physics-world-pushed world) t))
        (wake-handle world handle)
        (values)))))

(defun physics-body-force (world handle)
  "The force, N, HANDLE's body has been given for the next step, as three values. #F0RC3S"
  (check-world world 'physics-body-force)
  (resolve-handle world handle)
  (let ((pushes (physics-world-pushes world)) (p (* 4 (handle-index handle))))
    (if pushes
        (values (aref pushes p) (aref pushes (+ p 1)) (aref pushes (+ p 2)))
        (values 0.0 0.0 0.0))))

(defun set-physics-body-gravity-scale (world handle scale)
  "Make HANDLE's body feel SCALE times the world's gravity from the next step on, and wake it. A
scale beyond +physics-max-gravity-scale+ in magnitude is refused naming :gravity-scale, and one
other than 1 in a world without :forces with physics-feature-omitted. #F0RC3S"
  (check-idle world 'set-physics-body-gravity-scale)
  (resolve-handle world handle)
  (let ((s (checked-gravity-scale world 'set-physics-body-gravity-scale scale)))
    (note-gravity-scale world handle s)
    (let ((row (wake-handle world handle)))
      (setf (aref (body-columns-sleep-time (physics-world-awake world)) row) 0.0))
    (values)))

(defun physics-body-gravity-scale (world handle)
  "The gravity scale of HANDLE's body: 1 unless it was given another. #F0RC3S"
  (check-world world 'physics-body-gravity-scale)
  (resolve-handle world handle)
  (let ((pushes (physics-world-pushes world)))
    (if pushes (aref pushes (+ 3 (* 4 (handle-index handle)))) 1.0)))
;; Forces for the next step, and gravity by the body:1 ends here

;; [[file:../physics.org::#K1N3BX][Kinematic boxes are posted for one step:1]]
(define-physics-layout box-columns
  "Kinematic boxes posted by the client for the next step. #K1N3BX"
  (min-x single-float) (min-y single-float) (min-z single-float)
  (max-x single-float) (max-y single-float) (max-z single-float)
  (vx single-float) (vy single-float) (vz single-float) (id fixnum) (filter fixnum))

(defun post-physics-box (world x y z hx hy hz &key (vx 0) (vy 0) (vz 0) owner
                                                (category +default-category+) (mask +all-categories+))
  "Post a kinematic box centred at X Y Z with half-extents HX HY HZ, moving at VX VY VZ, for the
next step only. OWNER, any object, keeps the box's contacts persistent across steps and comes
back with its hit events. CATEGORY and MASK filter the bodies it touches ([[#F1LT3R]]). #K1N3BX"
  (check-idle world 'post-physics-box)
  (require-physics-feature world :boxes 'post-physics-box)
  (let ((filter (checked-filter world category mask))
        (x (finite-f32 :x x world)) (y (finite-f32 :y y world)) (z (finite-f32 :z z world))
        (hx (finite-f32 :hx hx world)) (hy (finite-f32 :hy hy world)) (hz (finite-f32 :hz hz world))
        (vx (finite-f32 :vx vx world)) (vy (finite-f32 :vy vy world)) (vz (finite-f32 :vz vz world)))
    (flet ((half-extent (name v)
             (unless (< 0 v 1024)
               (error 'invalid-physics-parameter :world world :name name :value v :expected "in (0, 1024) m"))))
      (half-extent :hx hx) (half-extent :hy hy) (half-extent :hz hz))
    (check-coordinate :x x world) (check-coordinate :y y world) (check-coordinate :z z world)
    (check-velocity vx vy vz (physics-world-max-speed world) world)
    (let* ((boxes (physics-world-boxes world))
           (row (box-columns-append boxes))
           (ids (physics-world-box-ids world))
           (id (if owner
                   (or (gethash owner ids) (setf (gethash owner ids) (1+ (hash-table-count ids))))
                   (logior (ash 1 33) row))))
      (with-box-columns (min-x min-y min-z max-x max-y max-z (bvx vx) (bvy vy) (bvz vz) (bid id)
                         (bfilter filter))
          boxes
        (setf (aref min-x row) (- x hx) (aref min-y row) (- y hy) (aref min-z row) (- z hz)
              (aref max-x row) (+ x hx) (aref max-y row) (+ y hy) (aref max-z row) (+ z hz)
              (aref bvx row) vx (aref bvy row) vy (aref bvz row) vz (aref bid row) id
              (aref bfilter row) filter))
      (note-filter world filter)
      (let ((owners (physics-world-box-owners world)))
        (when (>= row (length owners))
          (setf owners (replace (make-array (* 2 (1+ row)) :initial-element nil) owners)
                (physics-world-box-owners world) owners))
        (setf (svref owners row) owner))
      row)))

(defun box-owner (world key)
  "The owner of the posted box named in contact KEY, or NIL. #K1N3BX"
  (let ((id (ldb (byte 34 0) key)) (boxes (physics-world-boxes world)))
    (dotimes (b (box-columns-length boxes))
      (when (= (aref (box-columns-id boxes) b) id)
        (return (svref (physics-world-box-owners world) b))))))
;; Kinematic boxes are posted for one step:1 ends here

;; [[file:../physics.org::#F1LT3R][Categories and masks choose who meets whom:1]]
(declaim (inline filter-word filters-meet-p rows-meet-p))
(defun filter-word (category mask)
  "CATEGORY and MASK as one word, each exclusive-ored with its default so that the default filter
is 0: the category in bits 0 to 15, the mask in bits 16 to 31. #F1LT3R"
  (declare (type (unsigned-byte 16) category mask))
  (logior (logxor category +default-category+) (ash (logxor mask +all-categories+) 16)))

(defun filters-meet-p (a b)
  "True when the bodies or boxes of filter words A and B meet: each belongs to a class the
other's mask holds. #F1LT3R"
  (declare (type (unsigned-byte 32) a b) #.+kernel-policy+)
  (let ((ca (logxor (ldb (byte 16 0) a) +default-category+)) (ma (logxor (ldb (byte 16 16) a) +all-categories+))
        (cb (logxor (ldb (byte 16 0) b) +default-category+)) (mb (logxor (ldb (byte 16 16) b) +all-categories+)))
    (and (logtest ca mb) (logtest cb ma))))

(defun rows-meet-p (filtering flags-a flags-b)
  "True when two rows of body flags FLAGS-A and FLAGS-B meet, or when FILTERING, the world's
note that some filter is in use, is false. #F1LT3R"
  (declare (type fixnum flags-a flags-b) #.+kernel-policy+)
  (or (not filtering)
      (filters-meet-p (ldb (byte 32 +flag-filter-shift+) flags-a) (ldb (byte 32 +flag-filter-shift+) flags-b))))

(defun checked-filter (world category mask)
  "The filter word of CATEGORY and MASK, each an integer from 0 to 65535, or an
invalid-physics-parameter error naming :category or :mask. #F1LT3R"
  (flet ((one (name value)
           (unless (typep value '(integer 0 #xFFFF))
             (error 'invalid-physics-parameter :world world :name name :value value
                                               :expected "an integer from 0 to 65535 (sixteen class bits)"))))
    (one :category category)
    (one :mask mask)
    (filter-word category mask)))

(defun note-filter (world word)
  "Turn on WORLD's filtering once a body or box has the filter WORD of its own. #F1LT3R"
  (unless (zerop word) (setf (physics-world-filtering world) t))
  word)

(defun physics-body-filter (world handle)
  "The category and the mask of HANDLE's body, as two values. #F1LT3R"
  (check-world world 'physics-body-filter)
  (multiple-value-bind (set row) (resolve-handle world handle)
    (let ((word (ldb (byte 32 +flag-filter-shift+) (aref (body-columns-flags (set-buffer world set)) row))))
      (values (logxor (ldb (byte 16 0) word) +default-category+)
              (logxor (ldb (byte 16 16) word) +all-categories+)))))

(defun set-physics-body-filter (world handle &key category mask)
  "Give HANDLE's body the CATEGORY and MASK given (each kept when not), both checked before
either is written; wake it and the sleepers within its reach, and have the next step build its
pair list again, so that pairs that no longer meet lose their contacts there. #F1LT3R"
  (check-idle world 'set-physics-body-filter)
  (multiple-value-bind (old-category old-mask) (physics-body-filter world handle)
    (let* ((word (checked-filter world (or category old-category) (or mask old-mask)))
           (row (wake-handle world handle))
           (awake (physics-world-awake world))
           (sleeping (physics-world-sleeping world)))
      (setf (ldb (byte 32 +flag-filter-shift+) (aref (body-columns-flags awake) row)) word)
      (note-filter world word)
      ;; the pair list's structure is defined with the pair phase, later on the page
      (locally (declare (notinline (setf pair-list-rows)))
        (setf (pair-list-rows (physics-world-pair-list world)) -1))
      ;; the sleepers it touches: woken last row first, so no row moved is visited again
      (let ((x (aref (body-columns-x awake) row)) (y (aref (body-columns-y awake) row))
            (z (aref (body-columns-z awake) row))
            (reach (+ (aref (body-columns-radius awake) row) (f32 (physics-world-margin world)))))
        (loop for s from (1- (body-columns-length sleeping)) downto 0
              do (let ((dx (- (aref (body-columns-x sleeping) s) x)) (dy (- (aref (body-columns-y sleeping) s) y))
                       (dz (- (aref (body-columns-z sleeping) s) z))
                       (r (+ reach (aref (body-columns-radius sleeping) s))))
                   (when (< (+ (* dx dx) (* dy dy) (* dz dz)) (* r r))
                     (wake-physics-body world s)))))
      handle)))
;; Categories and masks choose who meets whom:1 ends here

;; [[file:../physics.org::#S3NS0R][Sensors report who enters and who leaves:1]]
(defstruct (physics-sensor (:constructor make-physics-sensor
                               (id min-x min-y min-z max-x max-y max-z filter owner)))
  "A lasting sensor box: its id, bounds and filter word, its owner, and the bodies inside it
(INSIDE, each handle to the step it was last seen inside). #S3NS0R"
  (id 0 :type fixnum)
  (min-x 0.0 :type single-float) (min-y 0.0 :type single-float) (min-z 0.0 :type single-float)
  (max-x 0.0 :type single-float) (max-y 0.0 :type single-float) (max-z 0.0 :type single-float)
  (filter 0 :type fixnum)
  (owner nil)
  (inside (make-hash-table) :type hash-table))

(defconstant +event-sensor-enter+ 8 "Event code of :sensor-enter. #S3NS0R")

(defconstant +event-sensor-leave+ 9 "Event code of :sensor-leave. #S3NS0R")

(defun add-physics-sensor (world x y z hx hy hz &key (category +default-category+)
                                                  (mask +all-categories+) owner)
  "Add a lasting sensor box centred at X Y Z with half-extents HX HY HZ, meeting the bodies that
CATEGORY and MASK meet, and return its id. Its :sensor-enter and :sensor-leave events carry
OWNER as their datum. #S3NS0R"
  (check-idle world 'add-physics-sensor)
  (let ((x (finite-f32 :x x world)) (y (finite-f32 :y y world)) (z (finite-f32 :z z world))
        (hx (finite-f32 :hx hx world)) (hy (finite-f32 :hy hy world)) (hz (finite-f32 :hz hz world)))
    (flet ((half-extent (name v)
             (unless (< 0 v 1024)
               (error 'invalid-physics-parameter :world world :name name :value v :expected "in (0, 1024) m"))))
      (half-extent :hx hx) (half-extent :hy hy) (half-extent :hz hz))
    (check-coordinate :x x world) (check-coordinate :y y world) (check-coordinate :z z world)
    (let* ((filter (checked-filter world category mask))
           (id (incf (physics-world-sensor-counter world)))
           (sensor (make-physics-sensor id (- x hx) (- y hy) (- z hz) (+ x hx) (+ y hy) (+ z hz) filter owner)))
      (note-filter world filter)
      (setf (slot-value world 'event-mask)
            (logior (world-event-mask world) (ash 1 +event-sensor-enter+) (ash 1 +event-sensor-leave+))
            (physics-world-sensors world) (append (physics-world-sensors world) (list sensor)))
      id)))

(defun find-sensor (world id operation)
  "The sensor of WORLD whose id is ID, or an invalid-physics-parameter error naming :sensor. #S3NS0R"
  (or (find id (physics-world-sensors world) :key #'physics-sensor-id)
      (error 'invalid-physics-parameter :world world :name :sensor :value id
                                        :expected (format nil "the id of a sensor of this world (~(~A~))" operation))))

(defun remove-physics-sensor (world id)
  "Remove WORLD's sensor ID, reporting nothing for the bodies inside it. #S3NS0R"
  (check-idle world 'remove-physics-sensor)
  (let ((sensor (find-sensor world id 'remove-physics-sensor)))
    (setf (physics-world-sensors world) (remove sensor (physics-world-sensors world)))
    id))

(defun physics-sensor-bodies (world id)
  "The handles of the bodies inside WORLD's sensor ID after the last step, in ascending order. #S3NS0R"
  (check-world world 'physics-sensor-bodies)
  (let ((handles '()))
    (maphash (lambda (h mark) (declare (ignore mark)) (push h handles))
             (physics-sensor-inside (find-sensor world id 'physics-sensor-bodies)))
    (sort handles #'<)))

(defun sense-set (world sensor buffer mark filtering)
  "Mark in SENSOR's set, as seen at step MARK, each body of BUFFER inside it, with a
:sensor-enter event for each that was not inside before. #S3NS0R"
  (declare (type physics-sensor sensor) (type body-columns buffer) (type fixnum mark) #.+kernel-policy+)
  (let ((x0 (physics-sensor-min-x sensor)) (y0 (physics-sensor-min-y sensor)) (z0 (physics-sensor-min-z sensor))
        (x1 (physics-sensor-max-x sensor)) (y1 (physics-sensor-max-y sensor)) (z1 (physics-sensor-max-z sensor))
        (word (ash (physics-sensor-filter sensor) +flag-filter-shift+))
        (inside (physics-sensor-inside sensor)) (id (physics-sensor-id sensor)))
    (declare (type single-float x0 y0 z0 x1 y1 z1) (type fixnum word id))
    (with-body-columns (x y z vx vy vz radius flags handle) buffer
      (dotimes (i (body-columns-length buffer))
        (let* ((cx (aref x i)) (cy (aref y i)) (cz (aref z i)) (r (aref radius i))
               (dx (max (- x0 cx) (- cx x1) 0.0)) (dy (max (- y0 cy) (- cy y1) 0.0))
               (dz (max (- z0 cz) (- cz z1) 0.0)))
          (declare (type single-float cx cy cz r dx dy dz))
          (when (and (< (+ (* dx dx) (* dy dy) (* dz dz)) (* r r))
                     (rows-meet-p filtering (aref flags i) word))
            (let ((h (aref handle i)))
              (unless (gethash h inside)
                (push-event world +event-sensor-enter+ h id cx cy cz
                            (fsqrt (+ (* (aref vx i) (aref vx i)) (* (aref vy i) (aref vy i))
                                      (* (aref vz i) (aref vz i))))
                            (physics-sensor-owner sensor)))
              (setf (gethash h inside) mark))))))))

(defun sense-phase (world)
  "After a step's phases: each sensor of WORLD, in the order they were added, marks the bodies
inside it (the awake set, then the sleeping one), reporting those that entered, then reports
and forgets those no longer inside. #S3NS0R"
  (let ((mark (physics-world-step-count world)) (filtering (physics-world-filtering world))
        (ids (physics-world-ids world)))
    (dolist (sensor (physics-world-sensors world))
      (let ((inside (physics-sensor-inside sensor)))
        (sense-set world sensor (physics-world-awake world) mark filtering)
        (sense-set world sensor (physics-world-sleeping world) mark filtering)
        (with-hash-table-iterator (next inside)
          (loop (multiple-value-bind (more h seen) (next)
                  (unless more (return))
                  (unless (= seen mark)
                    (remhash h inside)
                    (if (handle-status ids h)
                        (push-event world +event-sensor-leave+ h (physics-sensor-id sensor)
                                    (* 0.5 (+ (physics-sensor-min-x sensor) (physics-sensor-max-x sensor)))
                                    (* 0.5 (+ (physics-sensor-min-y sensor) (physics-sensor-max-y sensor)))
                                    (* 0.5 (+ (physics-sensor-min-z sensor) (physics-sensor-max-z sensor)))
                                    0.0 (physics-sensor-owner sensor))
                        (multiple-value-bind (x y z) (physics-body-position world h)
                          (multiple-value-bind (vx vy vz) (physics-body-velocity world h)
                            (push-event world +event-sensor-leave+ h (physics-sensor-id sensor) x y z
                                        (sqrt (+ (* vx vx) (* vy vy) (* vz vz)))
                                        (physics-sensor-owner sensor)))))))))))
    world))
;; Sensors report who enters and who leaves:1 ends here

;; [[file:../physics.org::#G3NCNT][Contacts are made speculatively:1]]
(declaim (inline refresh-contact))
(defun refresh-contact (contacts row step place nx ny nz separation px py pz kvx kvy kvz)
  "Give contact ROW of CONTACTS this step's geometry, the impulses it carries dropped when its
normal turned, and stamp it seen at STEP with PLACE in the step's order; return true, or NIL,
changing nothing, when it was seen at STEP already. #G3NCNT"
  (declare (type contact-columns contacts) (type index row place) (type fixnum step)
           (type single-float nx ny nz separation px py pz kvx kvy kvz) #.+kernel-policy+)
  (with-contact-columns (seen order geometry) contacts
    (let ((g (geometry-start row)))
      (unless (= (aref seen row) step)
        (setf (aref order row) place)
        ;; carried impulses only make sense along a normal close to the one they were found on
        (when (< (+ (* nx (contact-at geometry g nx)) (* ny (contact-at geometry g ny))
                    (* nz (contact-at geometry g nz)))
                 0.9)
          (setf (contact-at geometry g normal-impulse) 0.0
                (contact-at geometry g tangent-impulse-1) 0.0 (contact-at geometry g tangent-impulse-2) 0.0
                (contact-at geometry g rolling-impulse-x) 0.0 (contact-at geometry g rolling-impulse-y) 0.0
                (contact-at geometry g rolling-impulse-z) 0.0 (contact-at geometry g spin-impulse) 0.0))
        (setf (aref seen row) step
              (contact-at geometry g nx) nx (contact-at geometry g ny) ny (contact-at geometry g nz) nz (contact-at geometry g separation) separation
              (contact-at geometry g px) px (contact-at geometry g py) py (contact-at geometry g pz) pz
              (contact-at geometry g kvx) kvx (contact-at geometry g kvy) kvy (contact-at geometry g kvz) kvz)
        t))))
(declaim (notinline refresh-contact))

(declaim (inline touch-contact))
(defun touch-contact (contacts table key kind handle-a handle-b nx ny nz separation px py pz kvx kvy kvz)
  "Refresh the contact under KEY in CONTACTS and TABLE with this step's geometry, or add it with
zero impulses; the row under the table's cursor is tried before the table. #G3NCNT"
  (declare (type contact-columns contacts) (type contact-table table) (type fixnum key kind handle-a handle-b)
           (type single-float nx ny nz separation px py pz kvx kvy kvz) #.+kernel-policy+
           (inline refresh-contact))
  (let* ((step (contact-table-step table))
         (guess (contact-table-cursor table))
         (row (if (and (< guess (contact-columns-length contacts))
                       (= (aref (contact-columns-key contacts) guess) key))
                  guess
                  (progn (incf (contact-table-misses table))
                         (contact-table-find table key)))))
    (declare (type fixnum row step) (type index guess))
    (if (< row 0)
        (progn
          (setf row (contact-columns-append contacts))
          (contact-table-put table key row)
          (with-contact-columns ((a handle-a) (b handle-b) (k kind) (ky key)) contacts
            (setf (aref a row) handle-a (aref b row) handle-b (aref k row) kind (aref ky row) key)))
        (setf (contact-table-cursor table) (1+ row)))
    (when (refresh-contact contacts row step (contact-table-touched table)
                           nx ny nz separation px py pz kvx kvy kvz)
      (incf (contact-table-touched table)))
    row))
(declaim (notinline touch-contact))

(declaim (inline pair-impact-normal))
(defun pair-impact-normal (dx dy dz wx wy wz reach dt nx ny nz separation)
  "For two spheres whose centres are DX DY DZ apart, closing at the relative velocity WX WY WZ,
that touch when their centres are REACH apart: the line of centres when they touch (or after DT,
if later) as a unit normal, and the gap along it now. Without a touch ahead, NX NY NZ and
SEPARATION. #G3NCNT"
  (declare (type single-float dx dy dz wx wy wz reach dt nx ny nz separation))
  (let* ((a (+ (* wx wx) (* wy wy) (* wz wz)))
         (b (+ (* dx wx) (* dy wy) (* dz wz)))
         (c (- (+ (* dx dx) (* dy dy) (* dz dz)) (* reach reach)))
         (disc (- (* b b) (* a c))))
    (declare (type single-float a b c disc))
    (if (or (<= a 0.0) (<= disc 0.0) (>= b 0.0))
        (values nx ny nz separation)
        ;; |d + w t| = reach at the smaller root
        (let* ((time (min dt (/ (- (- b) (fsqrt disc)) a)))
               (qx (+ dx (* wx time))) (qy (+ dy (* wy time))) (qz (+ dz (* wz time)))
               (q (fsqrt (+ (* qx qx) (* qy qy) (* qz qz)))))
          (declare (type single-float time qx qy qz q))
          (if (> q 1e-6)
              (let ((mx (/ qx q)) (my (/ qy q)) (mz (/ qz q)))
                (values mx my mz (- (+ (* dx mx) (* dy my) (* dz mz)) reach)))
              (values nx ny nz separation))))))

(declaim (inline gravity-step))
(defun gravity-step (world dt)
  "The speed WORLD's gravity adds over DT seconds, the step of gravity that
speculative-distance grows an approach by. #G3NCNT"
  (declare (type single-float dt))
  (* dt (fsqrt (+ (expt (physics-world-gravity-x world) 2) (expt (physics-world-gravity-y world) 2)
                  (expt (physics-world-gravity-z world) 2)))))

(declaim (inline speculative-distance))
(defun speculative-distance (approach dt slop margin gravity-step)
  "How wide a gap a contact may have and still be made this step: four slops, plus the
distance the pair can close in DT at APPROACH speed grown by one step of gravity, but no
more than MARGIN. #G3NCNT"
  (declare (type single-float approach dt slop margin gravity-step))
  ;; (approach + |approach|)/2 is exactly max(approach, 0), without the branch that a pile's
  ;; approach speeds, as often positive as not, would mispredict
  (min margin (+ (* 4.0 slop) (* (+ (* 0.5 (+ approach (abs approach))) gravity-step) dt))))
;; Contacts are made speculatively:1 ends here

;; [[file:../physics.org::#G4R1D5][The grids of the awake and of the sleeping:1]]
(defun grid-cell-size (world)
  "The grid's cell edge: the largest diameter plus the margin and the pair list's skin, so every
pair within reach, or within the skin beyond it, lies in neighbouring cells. #G4R1D5"
  (+ (* 2 (physics-world-max-radius world)) (physics-world-margin world) (physics-world-pair-skin world)))

(defun sleeping-grid-of (world)
  "For each handle slot, which sleeping grid holds its body's live entry: 1 the settled grid, 2
the fresh one, 3 the newest one, 0 none; grown to the handle table's slots. #G4R1D5"
  (let ((of (physics-world-grid-of world))
        (slots (length (handle-table-set (physics-world-ids world)))))
    (declare (type fixnum-column of))
    (if (>= (length of) slots)
        of
        (setf (physics-world-grid-of world) (fixnum-room of slots :least 0)))))

(defun note-fresh-sleeper (world handle)
  "Note that HANDLE's body fell asleep: the newest grid takes it at its next build. #G4R1D5"
  (let ((handles (physics-world-newest-handles world)) (count (physics-world-newest-count world))
        (of (sleeping-grid-of world)))
    (declare (type fixnum-column handles of) (type fixnum count))
    (when (= (aref of (handle-index handle)) 1) (incf (physics-world-settled-stale world)))
    (setf handles (fixnum-room handles (1+ count)) (physics-world-newest-handles world) handles)
    (setf (aref handles count) handle
          (physics-world-newest-count world) (1+ count)
          (aref of (handle-index handle)) 3
          (physics-world-sleeping-grid-dirty world) t)
    handle))

(defun leave-sleeping-grids (world handle)
  "HANDLE's body leaves the sleeping set: its entry in any grid is dead from now on. #G4R1D5"
  (let ((of (sleeping-grid-of world)) (slot (handle-index handle)))
    (declare (type fixnum-column of))
    (when (= (aref of slot) 1) (incf (physics-world-settled-stale world)))
    (setf (aref of slot) 0)
    handle))

(defun take-listed-sleepers (world handles count mark)
  "Compact the first COUNT handles of HANDLES to those that name a sleeper whose grid mark is MARK,
each once, in their order; return how many are kept. #G4R1D5"
  (declare (type fixnum-column handles) (type fixnum count mark))
  (let* ((ids (physics-world-ids world))
         (sets (handle-table-set ids)) (generations (handle-table-generation ids))
         (of (sleeping-grid-of world))
         (kept 0))
    (declare (type fixnum-column sets generations of) (type fixnum kept))
    (dotimes (k count)
      (let* ((h (aref handles k)) (slot (handle-index h)))
        (when (and (= (aref sets slot) +set-sleeping+) (= (aref generations slot) (handle-generation h))
                   (= (aref of slot) mark))
          ;; -1 marks it taken, so a body listed twice is taken once
          (setf (aref of slot) -1 (aref handles kept) h)
          (incf kept))))
    (dotimes (k kept) (setf (aref of (handle-index (aref handles k))) mark))
    kept))

(defun build-listed-sleepers (world grid handles count)
  "Build GRID from the sleepers named by the first COUNT handles of HANDLES, their centres gathered
into the world's scratch columns; count them in the world's sleeping-grid work. #G4R1D5"
  (declare (type fixnum-column handles) (type fixnum count))
  (when (< (length (physics-world-fresh-x world)) count)
    (let ((room (max count (* 2 (length (physics-world-fresh-x world))))))
      (setf (physics-world-fresh-x world) (make-array room :element-type 'single-float)
            (physics-world-fresh-y world) (make-array room :element-type 'single-float)
            (physics-world-fresh-z world) (make-array room :element-type 'single-float))))
  (let ((locals (handle-table-local (physics-world-ids world)))
        (s (physics-world-sleeping world))
        (xs (physics-world-fresh-x world)) (ys (physics-world-fresh-y world)) (zs (physics-world-fresh-z world)))
    (declare (type fixnum-column locals) (type f32-column xs ys zs))
    (dotimes (k count)
      (let ((row (aref locals (handle-index (aref handles k)))))
        (setf (aref xs k) (aref (body-columns-x s) row)
              (aref ys k) (aref (body-columns-y s) row)
              (aref zs k) (aref (body-columns-z s) row))))
    (incf (physics-world-sleeping-grid-work world) count)
    (build-hash-grid grid (f32 (grid-cell-size world)) count xs ys zs handles)))

(defun sleeping-grids-spent-p (world)
  "True when WORLD's settled sleeping grid must be built again from every sleeper: the cell size
changed, or the fresh and newest sleepers, or the settled grid's dead entries, outnumber an
eighth of the settled grid (and 256). #G4R1D5"
  (let ((bound (max 256 (floor (physics-world-settled-count world) 8))))
    (or (/= (hash-grid-inv-cell (physics-world-sleeping-grid world)) (/ 1.0 (grid-cell-size world)))
        (> (+ (physics-world-fresh-count world) (physics-world-newest-count world)) bound)
        (> (physics-world-settled-stale world) bound))))

(defun ensure-sleeping-grid (world)
  "Bring the sleeping grids up to date. Bodies that fell asleep go into the newest grid, which is
built again, from them alone, whenever one more falls asleep. The newest sleepers join the fresh
grid, built again from both, when they outnumber an eighth of the fresh ones (and 32). The
settled grid is built again from every sleeper, and the other two emptied, when the cell size
changed, or when the fresh and newest sleepers, or the settled grid's dead entries, outnumber an
eighth of the settled grid (and 256). Return the settled grid. #G4R1D5"
  (let* ((grid (physics-world-sleeping-grid world))
         (fresh (physics-world-fresh-grid world))
         (newest (physics-world-newest-grid world))
         (size (grid-cell-size world))
         (s (physics-world-sleeping world))
         (of (sleeping-grid-of world)))
    (declare (type fixnum-column of))
    (cond ((sleeping-grids-spent-p world)
           (let ((n (body-columns-length s)) (handles (body-columns-handle s)))
             ;; room for every body the world has a slot for, so that the settled grid grows seldom
             (hash-grid-reserve grid (max n (length of)))
             (build-hash-grid grid size n (body-columns-x s) (body-columns-y s) (body-columns-z s) handles)
             (dotimes (i n) (setf (aref of (handle-index (aref handles i))) 1))
             (incf (physics-world-sleeping-grid-work world) n)
             (setf (physics-world-settled-count world) n
                   (physics-world-settled-stale world) 0
                   (physics-world-fresh-count world) 0
                   (physics-world-newest-count world) 0)
             (build-hash-grid fresh size 0 (body-columns-x s) (body-columns-y s) (body-columns-z s) handles)
             (build-hash-grid newest size 0 (body-columns-x s) (body-columns-y s) (body-columns-z s) handles)
             (setf (physics-world-sleeping-grid-dirty world) nil)))
          ((physics-world-sleeping-grid-dirty world)
           (let ((kept (take-listed-sleepers world (physics-world-newest-handles world)
                                             (physics-world-newest-count world) 3)))
             (declare (type fixnum kept))
             (setf (physics-world-newest-count world) kept)
             (if (<= kept (max 32 (floor (physics-world-fresh-count world) 8)))
                 (build-listed-sleepers world newest (physics-world-newest-handles world) kept)
                 ;; the newest join the fresh list, which is compacted and built again
                 (let* ((count (physics-world-fresh-count world))
                        (handles (setf (physics-world-fresh-handles world)
                                       (fixnum-room (physics-world-fresh-handles world) (+ count kept) :keep count)))
                        (newest-handles (physics-world-newest-handles world)))
                   (declare (type fixnum-column handles newest-handles) (type fixnum count))
                   (dotimes (k kept)
                     (let ((h (aref newest-handles k)))
                       (setf (aref handles (+ count k)) h (aref of (handle-index h)) 2)))
                   (let ((taken (take-listed-sleepers world handles (+ count kept) 2)))
                     (setf (physics-world-fresh-count world) taken (physics-world-newest-count world) 0)
                     (build-listed-sleepers world fresh handles taken)
                     (build-listed-sleepers world newest newest-handles 0)))))
           (setf (physics-world-sleeping-grid-dirty world) nil)))
    grid))

(defmacro do-sleeping-neighbours ((item world x y z &key (span 1)) &body body)
  "Run BODY with ITEM bound to the handle of each live entry of WORLD's sleeping grids, settled,
fresh and newest, whose cell lies within SPAN cells of point X Y Z. An entry is live when its grid
is the one that holds its body now; whether the handle still names a sleeper is BODY's to ask. #G4R1D5"
  (let ((visit (gensym "VISIT")) (of (gensym "OF")))
    `(let ((,of (physics-world-grid-of ,world)))
       (declare (type fixnum-column ,of))
       (flet ((,visit (,item) (declare (type fixnum ,item)) ,@body))
         (declare (inline ,visit))
         (do-grid-neighbours (,item (physics-world-sleeping-grid ,world) ,x ,y ,z :span ,span)
           (when (= 1 (aref ,of (handle-index ,item))) (,visit ,item)))
         (do-grid-neighbours (,item (physics-world-fresh-grid ,world) ,x ,y ,z :span ,span)
           (when (= 2 (aref ,of (handle-index ,item))) (,visit ,item)))
         (do-grid-neighbours (,item (physics-world-newest-grid ,world) ,x ,y ,z :span ,span)
           (when (= 3 (aref ,of (handle-index ,item))) (,visit ,item)))))))

;; the 701 ... 1 gaps are Ciura's: a few sleepers are sorted by the last gap alone, as by insertion
(declaim (inline sort-sleepers-by-row))
(defun sort-sleepers-by-row (world handles count)
  "Sort the first COUNT handles of HANDLES, each naming one of WORLD's sleepers, by the sleepers'
rows in the sleeping buffer, in place and allocating nothing (Shell's sort). #G4R1D5"
  (declare (type fixnum-column handles) (type index count) #.+kernel-policy+)
  (let ((locals (handle-table-local (physics-world-ids world))))
    (declare (type fixnum-column locals))
    (dolist (gap '(701 301 132 57 23 10 4 1) handles)
      (declare (type index gap))
      (loop for i of-type index from gap below count
            do (let* ((h (aref handles i)) (key (aref locals (handle-index h))) (j i))
                 (declare (type fixnum h key) (type index j))
                 (loop while (and (>= j gap) (> (aref locals (handle-index (aref handles (- j gap)))) key))
                       do (setf (aref handles j) (aref handles (- j gap)))
                          (decf j gap))
                 (setf (aref handles j) h))))))

(defmacro do-sleepers-in-row-order ((item world x y z &key (span 1)) test &body body)
  "Run BODY with ITEM bound to the handle of each live entry of WORLD's sleeping grids whose cell
lies within SPAN cells of point X Y Z and for which TEST (ITEM bound) is true, in the order of
the sleepers' rows in the sleeping buffer as they were when TEST had been asked of every entry.
TEST is asked of every entry before BODY runs for any, so BODY may wake the sleepers it is given
(which moves rows); and what BODY meets, in what order, does not hang on which grid holds a
sleeper or where in it. #G4R1D5"
  (let ((found (gensym "FOUND")) (count (gensym "COUNT")) (w (gensym "WORLD")) (k (gensym "K")))
    `(let* ((,w ,world) (,found (physics-world-sleepers-found ,w)) (,count 0))
       (declare (type fixnum-column ,found) (type index ,count))
       (do-sleeping-neighbours (,item ,w ,x ,y ,z :span ,span)
         (when ,test
           (when (= ,count (length ,found))
             (setf ,found (fixnum-room ,found (1+ ,count)) (physics-world-sleepers-found ,w) ,found))
           (setf (aref ,found ,count) ,item)
           (incf ,count)))
       (sort-sleepers-by-row ,w ,found ,count)
       (dotimes (,k ,count)
         (let ((,item (aref ,found ,k)))
           (declare (type fixnum ,item))
           ,@body)))))

(defun grid-phase (world)
  "The grid phase: find the pair list's loose rows; unless the list holds and the awake grid still has
the cells of the list's build, bucket the awake bodies by cell, and put the awake rows in the
order of a dense grid when they have drifted out of it. #G4R1D5"
  (let* ((awake (physics-world-awake world))
         (grid (physics-world-awake-grid world))
         (n (body-columns-length awake)))
    (unless (pair-list-survey world)
      (build-hash-grid grid (grid-cell-size world) n
                       (body-columns-x awake) (body-columns-y awake) (body-columns-z awake)
                       ;; the awake grid's items are rows: an identity column of row numbers
                       (awake-row-identities world n))
      (setf (physics-world-awake-grid-step world) (contact-table-step (physics-world-contact-table world)))
      ;; the room a sort needs grows with the awake buffer, so sorting itself never allocates
      (body-columns-ensure-capacity (physics-world-awake-scratch world) (body-columns-capacity awake))
      (when (< (length (physics-world-row-places world)) (body-columns-capacity awake))
        (setf (physics-world-row-places world)
              (make-array (body-columns-capacity awake) :element-type 'fixnum)
              (physics-world-undo-rows world)
              (make-array (body-columns-capacity awake) :element-type 'fixnum)))
      (when (and (hash-grid-dense grid) (> (grid-order-breaks grid n) (floor n 16)))
        (sort-awake-rows world grid n)
        ;; the moved rows hold other bodies now: count them loose
        (pair-list-survey world)))
    (ensure-sleeping-grid world)))

(defun grid-order-breaks (grid n)
  "How many of the first N items of GRID's order do not follow the item before them. #G4R1D5"
  (declare (type hash-grid grid) (type index n) #.+kernel-policy+)
  (let ((items (hash-grid-items grid)) (breaks 0))
    (declare (type fixnum breaks))
    (loop for e of-type fixnum from 1 below n
          unless (= (aref items e) (1+ (aref items (1- e)))) do (incf breaks))
    breaks))

(defun sort-awake-rows (world grid n)
  "Move each of the N awake rows to its place in GRID's order, patch every awake handle's
forwarding address, and make the grid's items the new rows. #G4R1D5"
  (declare (type hash-grid grid) (type index n) #.+kernel-policy+)
  (let ((awake (physics-world-awake world))
        (items (hash-grid-items grid))
        (locals (handle-table-local (physics-world-ids world))))
    (declare (type body-columns awake) (type fixnum-column items locals))
    ;; in a step, what the row that each place receives was, so a failed step can undo the move
    (when (physics-world-undo-open world)
      (replace (the fixnum-column (physics-world-undo-rows world)) items :end2 n)
      (setf (physics-world-undo-sorted world) n))
    (let ((places (physics-world-row-places world)))
      (declare (type fixnum-column places))
      (dotimes (e n) (setf (aref places (aref items e)) e))
      ;; the rows' moves in pieces, one a worker ([[#SPL1T5]]): each row goes to its own place
      (flet ((runner (move rows) (run-row-pieces world rows :sort-rows move)))
        (declare (dynamic-extent #'runner))
        (body-columns-permute awake (physics-world-awake-scratch world) places n #'runner))
      (let ((handle (body-columns-handle awake)))
        (dotimes (i n)
          (setf (aref locals (handle-index (aref handle i))) i
                (aref items i) i))))
    world))

(defvar *row-identities* (make-array 0 :element-type 'fixnum)
  "0, 1, 2, ...: the identity column the awake grid is built from. #G4R1D5")

(defun awake-row-identities (world n)
  "A fixnum column holding 0 .. N-1. #G4R1D5"
  (declare (ignore world))
  (when (< (length *row-identities*) n)
    (let ((ids (make-array (max n (* 2 (length *row-identities*)) 1024) :element-type 'fixnum)))
      (dotimes (i (length ids)) (setf (aref ids i) i))
      (setf *row-identities* ids)))
  *row-identities*)
;; The grids of the awake and of the sleeping:1 ends here

;; [[file:../physics.org::#W4K3PH][Fast bodies and moving boxes wake what they reach:1]]
(declaim (inline sleeper-in-reach-p))
(defun sleeper-in-reach-p (world h x y z reach-extra box-p min-x min-y min-z max-x max-y max-z)
  "True when H still names a sleeper of WORLD whose surface lies within REACH-EXTRA of the point X
Y Z, or with BOX-P of the box MIN-X .. MAX-Z. #W4K3PH"
  (declare (type single-float x y z reach-extra min-x min-y min-z max-x max-y max-z))
  (let ((ids (physics-world-ids world))
        (sleeping (physics-world-sleeping world))
        (slot (handle-index h)))
    (and (= (aref (handle-table-set ids) slot) +set-sleeping+)
         (= (aref (handle-table-generation ids) slot) (handle-generation h))
         (let* ((row (aref (handle-table-local ids) slot))
                (sx (aref (body-columns-x sleeping) row))
                (sy (aref (body-columns-y sleeping) row))
                (sz (aref (body-columns-z sleeping) row))
                (sr (aref (body-columns-radius sleeping) row)))
           (if box-p
               (let ((dx (- sx (max min-x (min max-x sx))))
                     (dy (- sy (max min-y (min max-y sy))))
                     (dz (- sz (max min-z (min max-z sz)))))
                 (<= (+ (* dx dx) (* dy dy) (* dz dz))
                     (* (+ sr reach-extra) (+ sr reach-extra))))
               (let ((dx (- sx x)) (dy (- sy y)) (dz (- sz z))
                     (reach (+ sr reach-extra)))
                 (< (+ (* dx dx) (* dy dy) (* dz dz)) (* reach reach))))))))

(defun wake-within-reach (world x y z reach-extra span box-p min-x min-y min-z max-x max-y max-z)
  "Wake every sleeper of WORLD in reach of the point X Y Z or, with BOX-P, of the box MIN-X ..
MAX-Z (sleeper-in-reach-p), looking SPAN cells of the sleeping grid around the point; return how
many woke. #W4K3PH"
  (declare (type single-float x y z reach-extra min-x min-y min-z max-x max-y max-z))
  (let ((ids (physics-world-ids world))
        (woken 0))
    (declare (type fixnum woken))
    ;; the sleepers within reach are woken in the order of their sleeping rows,
    ;; which is the order they join the awake rows in: it does not hang on the grids
    (do-sleepers-in-row-order
        (h world x y z :span span)
        (sleeper-in-reach-p world h x y z reach-extra box-p min-x min-y min-z max-x max-y max-z)
      ;; each still sleeps: waking one moves no other out of the sleeping set
      (wake-physics-body world (aref (handle-table-local ids) (handle-index h)))
      (incf woken))
    woken))

(defun wake-near-added (world)
  "Wake the sleepers each body added to WORLD since the last step overlaps deeper than the slop,
so that it meets them as awake bodies from its first substep; return how many woke. #W4K3PH"
  (let ((ids (physics-world-ids world))
        (added (physics-world-added world))
        (slop (f32 (physics-world-slop world)))
        (woken 0))
    (declare (type fixnum-column added) (type single-float slop) (type fixnum woken))
    (dotimes (k (physics-world-added-count world) woken)
      (let* ((h (aref added k)) (slot (handle-index h)))
        (when (and (= (aref (handle-table-set ids) slot) +set-awake+)
                   (= (aref (handle-table-generation ids) slot) (handle-generation h)))
          (let ((row (aref (handle-table-local ids) slot)))
            (with-body-columns (x y z radius flags) (physics-world-awake world)
              (when (zerop (logand (aref flags row) +flag-terrain-only+))
                (incf woken (wake-within-reach world (aref x row) (aref y row) (aref z row)
                                               (- (aref radius row) slop)
                                               1 nil 0.0 0.0 0.0 0.0 0.0 0.0))))))))))

(defun wake-near-fast-bodies (world n)
  "Wake the sleepers within the margin plus one step's travel of each of the first N awake bodies
of WORLD faster than the wake speed; return how many woke. #W4K3PH"
  (let ((margin (f32 (physics-world-margin world)))
        (dt (physics-world-current-dt world))
        (wake2 (f32 (expt (physics-world-wake-speed world) 2)))
        (rmax (f32 (physics-world-max-radius world)))
        (inv (hash-grid-inv-cell (physics-world-sleeping-grid world)))
        (woken 0))
    (declare (type single-float margin wake2 dt rmax) (type fixnum woken))
    ;; a body woken is appended to the awake buffer, which grows then: its columns are
    ;; read again for each row
    (dotimes (i n woken)
      (with-body-columns (x y z vx vy vz radius flags) (physics-world-awake world)
        (when (and (> (+ (* (aref vx i) (aref vx i)) (* (aref vy i) (aref vy i))
                         (* (aref vz i) (aref vz i)))
                      wake2)
                   ;; a box meets the terrain alone as a water drop does, but wakes ([[#BXPUSH]])
                   (or (zerop (logand (aref flags i) +flag-terrain-only+))
                       (logtest (aref flags i) +flag-box-shape+)))
          (let ((extra (+ (aref radius i) margin
                          (* dt (fsqrt (+ (* (aref vx i) (aref vx i)) (* (aref vy i) (aref vy i))
                                          (* (aref vz i) (aref vz i))))))))
            ;; a sleeper within reach is at most EXTRA plus the largest radius away, so
            ;; its cell is at most that many cell edges from the body's, rounded up: one
            ;; cell unless the body travels more than the skin in a step
            (incf woken (wake-within-reach world (aref x i) (aref y i) (aref z i) extra
                                           (ceiling (* (+ extra rmax) inv))
                                           nil 0.0 0.0 0.0 0.0 0.0 0.0))))))))

(defun wake-near-moving-boxes (world)
  "Wake the sleepers within the margin plus one step's travel of each moving box of WORLD; return
how many woke. #W4K3PH"
  (let ((margin (f32 (physics-world-margin world)))
        (dt (physics-world-current-dt world))
        (boxes (physics-world-boxes world))
        (inv (hash-grid-inv-cell (physics-world-sleeping-grid world)))
        (woken 0))
    (declare (type single-float margin dt) (type fixnum woken))
    (with-box-columns (min-x min-y min-z max-x max-y max-z vx vy vz) boxes
      (dotimes (b (box-columns-length boxes) woken)
        (when (or (/= 0 (aref vx b)) (/= 0 (aref vy b)) (/= 0 (aref vz b)))
          (let* ((cx (* 0.5 (+ (aref min-x b) (aref max-x b))))
                 (cy (* 0.5 (+ (aref min-y b) (aref max-y b))))
                 (cz (* 0.5 (+ (aref min-z b) (aref max-z b))))
                 (travel (+ margin (* dt (fsqrt (+ (* (aref vx b) (aref vx b)) (* (aref vy b) (aref vy b))
                                                   (* (aref vz b) (aref vz b)))))))
                 (half (+ travel (max (- (aref max-x b) cx) (- (aref max-y b) cy) (- (aref max-z b) cz))))
                 (span (1+ (ceiling (* half inv)))))
            (incf woken (wake-within-reach world cx cy cz travel span t (aref min-x b) (aref min-y b)
                                           (aref min-z b) (aref max-x b) (aref max-y b) (aref max-z b)))))))))

(defun wake-phase (world)
  "The wake phase: awake bodies faster than the wake speed, and moving kinematic boxes, wake the
sleepers they can reach this step: within the margin plus one step's travel; bodies added since
the last step wake the sleepers they overlap deeper than the slop. Return how many woke. #W4K3PH"
  (let ((woken 0))
    (declare (type fixnum woken))
    (when (plusp (body-columns-length (physics-world-sleeping world)))
      (ensure-sleeping-grid world)
      ;; the awake bodies before any wakes: a body woken here is not asked to wake others
      (let ((n (body-columns-length (physics-world-awake world))))
        (incf woken (wake-near-added world))
        (incf woken (wake-near-fast-bodies world n))
        (incf woken (wake-near-moving-boxes world))))
    ;; a joint group wakes with any of its bodies ([[#J0SL3P]])
    (when (physics-world-joints world) (incf woken (wake-joint-groups world)))
    (setf (physics-world-added-count world) 0)
    woken))

(defun quiet-wake-phase (world)
  "The wake phase of a world without body contacts and boxes, where nothing reaches a sleeper: wake
nothing, forget the bodies added since the last step, and build the sleeping grids again only
when they are spent (sleeping-grids-spent-p), so that the fresh sleepers' list stays bounded.
Return 0. #W4K3PH"
  (when (sleeping-grids-spent-p world) (ensure-sleeping-grid world))
  (setf (physics-world-added-count world) 0)
  ;; but a body a caller woke wakes its joint group ([[#J0SL3P]])
  (when (physics-world-joints world) (wake-joint-groups world))
  0)

(defun note-added-body (world handle)
  "Remember that HANDLE's body was added (or moved, [[#T3LPRT]]) since the last step, for the wake
phase. A world that never sleeps has no wake phase to read and empty the list, and notes
nothing. #W4K3PH"
  (when (physics-world-sleep-enabled world)
    (let ((added (physics-world-added world)) (count (physics-world-added-count world)))
      (declare (type fixnum-column added) (type fixnum count))
      (setf added (fixnum-room added (1+ count) :least 16) (physics-world-added world) added)
      (setf (aref added count) handle
            (physics-world-added-count world) (1+ count))))
  handle)
;; Fast bodies and moving boxes wake what they reach:1 ends here

;; [[file:../physics.org::#P41RS7][Pairs: each awake pair once, and leaning on sleepers:1]]
(declaim (type (simple-array single-float (78)) +unit-directions+))
(sb-ext:defglobal +unit-directions+
  (let ((v (make-array 78 :element-type 'single-float)) (k 0))
    (loop for dz from -1 to 1 do
      (loop for dy from -1 to 1 do
        (loop for dx from -1 to 1 do
          (unless (= 0 dx dy dz)
            (let ((l (sqrt (float (+ (* dx dx) (* dy dy) (* dz dz)) 1.0))))
              (setf (aref v k) (/ dx l) (aref v (+ k 1)) (/ dy l) (aref v (+ k 2)) (/ dz l))
              (incf k 3))))))
    v)
  "The 26 unit directions towards the neighbours of a cell, three floats each. #P41RS7")

(declaim (inline coincident-direction))
(defun coincident-direction (ha hb)
  "For two bodies whose centres coincide, the offset in +unit-directions+ of the direction,
from body HA to body HB, that the pair is pushed apart along: fixed for the pair, varied
across pairs, and opposite when the two are named the other way round. #P41RS7"
  (declare (type fixnum ha hb))
  (let* ((lo (min (handle-index ha) (handle-index hb))) (hi (max (handle-index ha) (handle-index hb)))
         (k (mod (logxor (* lo 73856093) (* hi 19349663)) 26)))
    (declare (type (unsigned-byte 24) lo hi) (type (integer 0 25) k))
    ;; direction k and direction 25-k are opposite
    (* 3 (if (< (handle-index ha) (handle-index hb)) k (- 25 k)))))
;; Pairs: each awake pair once, and leaning on sleepers:1 ends here

;; [[file:../physics.org::#P41RS7][Pairs: each awake pair once, and leaning on sleepers:2]]
(defstruct (pair-list (:constructor make-pair-list ()))
  "The awake pairs kept between steps: every pair of awake rows whose centres lay within the
widest reach plus the skin when the list was built, packed as row A times 2^24 plus row B, in
the order the build found them; each row's centre then (ANCHORS, three floats a row), the
handle it held (HANDLES), the grid's cell edge, and per row whether it has strayed (LOOSE)
with the strayed rows in order (LOOSE-ROWS) and how many there are this step (LOOSE-COUNT,
-1 when the list must be built again). BUILDS counts the builds. STEP is the step whose pair
phase last used or built the list, BUILT-STEP the step that built it. CLEAR marks the rows with
no solid cell within their reach plus 0.45 skins of their anchor, in TERRAIN as it was after
TERRAIN-EDITS edits. LOOSE-GRID buckets the loose rows alone, from their centres gathered into
LOOSE-X, LOOSE-Y and LOOSE-Z. OVERLAPS counts, per row, the overlapping pairs taken this step against it.
EXAMINED counts the candidates within reach the last build listed. #P41RS7"
  (pairs (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (count 0 :type index)
  (rows -1 :type fixnum)
  (anchors (make-array 0 :element-type 'single-float) :type f32-column)
  (handles (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (loose (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (loose-rows (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (cell 0.0 :type single-float)
  (builds 0 :type index)
  (step -1 :type fixnum)
  (built-step -1 :type fixnum)
  (clear (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (terrain nil)
  (terrain-edits -1 :type fixnum)
  (loose-count -1 :type fixnum)
  (loose-grid (make-hash-grid) :type hash-grid)
  (loose-x (make-array 0 :element-type 'single-float) :type f32-column)
  (loose-y (make-array 0 :element-type 'single-float) :type f32-column)
  (loose-z (make-array 0 :element-type 'single-float) :type f32-column)
  (overlaps (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (examined 0 :type index))

(defun pair-list-room (plist rows)
  "Give every per-row column of PLIST, and its grid of loose rows, room for ROWS rows, keeping
what they hold and doubling when they grow, so that a step with no more rows than before
allocates nothing. #P41RS7"
  (declare (type pair-list plist) (type index rows))
  (when (< (length (pair-list-handles plist)) rows)
    (let ((rows (max rows (* 2 (length (pair-list-handles plist))) 64)))
      (flet ((grow (old size)
               (replace (make-array size :element-type (array-element-type old)) old)))
        (setf (pair-list-anchors plist) (grow (pair-list-anchors plist) (* 3 rows))
              (pair-list-handles plist) (grow (pair-list-handles plist) rows)
              (pair-list-clear plist) (grow (pair-list-clear plist) rows)
              (pair-list-loose plist) (grow (pair-list-loose plist) rows)
              (pair-list-loose-rows plist) (grow (pair-list-loose-rows plist) rows)
              (pair-list-loose-x plist) (grow (pair-list-loose-x plist) rows)
              (pair-list-loose-y plist) (grow (pair-list-loose-y plist) rows)
              (pair-list-loose-z plist) (grow (pair-list-loose-z plist) rows)
              (pair-list-overlaps plist) (grow (pair-list-overlaps plist) rows)))
      (hash-grid-reserve (pair-list-loose-grid plist) rows)))
  plist)
;; Pairs: each awake pair once, and leaning on sleepers:2 ends here

;; [[file:../physics.org::#P41RS7][Pairs: each awake pair once, and leaning on sleepers:3]]
(defun pair-list-strays (plist awake n cell reach)
  "Mark as loose each of the N awake rows that holds another body than when PLIST was built
(another handle, or a row added since) or whose centre lies farther than REACH from its
anchor, and each row the list knew that is gone; list the loose rows below N in order and
return how many. Return -1 when the list was never built or the cell edge changed, so it must
be built again. #P41RS7"
  (declare (type pair-list plist) (type body-columns awake) (type index n)
           (type single-float cell reach) #.+kernel-policy+)
  (let ((known (pair-list-rows plist)))
    (declare (type fixnum known))
    (if (or (< known 0) (/= (pair-list-cell plist) cell))
        -1
        (progn
          ;; room for a flag on every row, the list's and today's
          (pair-list-room plist (max n known))
          (let ((anchors (pair-list-anchors plist)) (handles (pair-list-handles plist))
                (loose (pair-list-loose plist)) (loose-rows (pair-list-loose-rows plist))
                (reach2 (* reach reach)) (count 0))
            (declare (type index count))
            (with-body-columns (x y z handle) awake
              (dotimes (i n)
                (if (or (>= i known) (/= (aref handle i) (aref handles i))
                        (let* ((o (* 3 i))
                               (dx (- (aref x i) (aref anchors o))) (dy (- (aref y i) (aref anchors (+ o 1))))
                               (dz (- (aref z i) (aref anchors (+ o 2)))))
                          (> (+ (* dx dx) (* dy dy) (* dz dz)) reach2)))
                    (setf (aref loose i) 1 (aref loose-rows count) i count (1+ count))
                    (setf (aref loose i) 0))))
            ;; rows the list names that no longer exist
            (loop for i of-type index from n below known do (setf (aref loose i) 1))
            count)))))

(defun pair-list-anchor (plist awake n cell)
  "Make PLIST describe the N awake rows as they are now: their centres as anchors, their
handles, CELL as the cell edge, and no row loose; count a build. #P41RS7"
  (declare (type pair-list plist) (type body-columns awake) (type index n) (type single-float cell))
  (pair-list-room plist n)
  (let ((anchors (pair-list-anchors plist)) (handles (pair-list-handles plist)))
    (with-body-columns (x y z handle) awake
      (dotimes (i n)
        (setf (aref anchors (* 3 i)) (aref x i) (aref anchors (+ (* 3 i) 1)) (aref y i)
              (aref anchors (+ (* 3 i) 2)) (aref z i) (aref handles i) (aref handle i)))))
  (fill (pair-list-loose plist) 0)
  (setf (pair-list-rows plist) n (pair-list-cell plist) cell)
  (incf (pair-list-builds plist))
  plist)

(defun pair-list-push (plist a b)
  "Append the pair of awake rows A and B to PLIST, doubling its room when full. #P41RS7"
  (declare (type pair-list plist) (type index a b) #.+kernel-policy+)
  (let ((k (pair-list-count plist)))
    (when (>= k (length (pair-list-pairs plist)))
      (setf (pair-list-pairs plist) (fixnum-room (pair-list-pairs plist) (1+ k) :least 1024)))
    (setf (aref (pair-list-pairs plist) k) (logior (ash a 24) b)
          (pair-list-count plist) (1+ k))))

(declaim (inline pair-list-holds-p))
(defun pair-list-holds-p (loose-count n)
  "True when a pair list with LOOSE-COUNT loose rows among N awake rows is still used: it was
built for this cell edge, and at most one row in 32 (or 16 rows) is loose. #P41RS7"
  (declare (type fixnum loose-count) (type index n))
  (and (>= loose-count 0) (<= loose-count (max 16 (floor n 32)))))

(defun pair-list-survey (world)
  "Mark WORLD's loose rows for this step (pair-list-strays) and keep their count in the pair
list. Return true when the list holds, no box is posted, and the awake grid was last built in
the step that built the list: then the grid's cells still serve the pair phase. #P41RS7"
  (let* ((plist (physics-world-pair-list world))
         (awake (physics-world-awake world))
         (n (body-columns-length awake))
         (loose (pair-list-strays plist awake n (f32 (grid-cell-size world))
                                  ;; a row may stray a little under half the skin: two such
                                  ;; rows still meet only if the build listed them
                                  (* 0.45 (f32 (physics-world-pair-skin world))))))
    (setf (pair-list-loose-count plist) loose)
    (and (pair-list-holds-p loose n)
         (= (physics-world-awake-grid-step world) (pair-list-built-step plist))
         (zerop (box-columns-length (physics-world-boxes world))))))
;; Pairs: each awake pair once, and leaning on sleepers:3 ends here

;; [[file:../physics.org::#P41RS7][Pairs: each awake pair once, and leaning on sleepers:4]]
(defconstant +overlaps-per-body+ 16
  "Most overlapping pairs with bodies no smaller than itself an awake body takes in one step;
past it the body is crowded and takes no more pairs with such bodies. #P41RS7")

(defconstant +crowded-walk-chunk+ 64
  "Places of a run a walk lists at a time once a walk of the same build has been refused. #P41RS7")

(declaim (inline overlap-room))
(defun overlap-room (overlaps i j radius)
  "True when the pair of awake rows I and J may be taken this step: the smaller row (both, for
equal radii) is not crowded, having taken fewer than +overlaps-per-body+ overlapping pairs as
OVERLAPS counts them. The pair phase counts a taken pair that overlaps against the smaller row,
from the distance it finds for the contact anyway. #P41RS7"
  (declare (type fixnum-column overlaps) (type index i j) (type f32-column radius) #.+kernel-policy+)
  (let ((ri (aref radius i)) (rj (aref radius j)))
    (and (or (> ri rj) (< (aref overlaps i) +overlaps-per-body+))
         (or (< ri rj) (< (aref overlaps j) +overlaps-per-body+)))))

(defstruct (pair-sink (:constructor make-pair-sink ()) (:copier nil))
  "What one worker's piece of the pair phase found: in LIST, a pair list of its own, the pairs it
listed, the candidates it examined and the overlaps it counted per awake row; COUNT touches, five
fixnums each in TOUCHES (the contact row its probe found or -1, the key, the kind, the two
handles) and seven floats each in GEOMETRY (the normal, the separation, the point); CURSOR, the
row it guesses next; NEAR, its neighbour scratch; for the terrain phase, PROBE, its own terrain
probe, and BURIED, the bodies its rows found buried. #P41RS7"
  (list (make-pair-list) :type pair-list :read-only t)
  (near (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (count 0 :type index)
  (cursor 0 :type index)
  (touches (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (geometry (make-array 0 :element-type 'single-float) :type f32-column)
  (probe (make-terrain-probe) :type terrain-probe :read-only t)
  (buried 0 :type fixnum)
  ;; for a merge in pieces ([[#P41P1C]]): the misses its walk counted, the touches of rows found
  ;; again and not yet seen this step, the first row it found again (-1 for none), the places of
  ;; its NEW touches of new contacts, and ORDER, the step's order its first fresh touch takes
  (misses 0 :type fixnum)
  (fresh 0 :type index)
  (first-row -1 :type fixnum)
  (new-count 0 :type index)
  (new (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (order 0 :type index))

(defun pair-sink-start (sink cursor)
  "Empty SINK's touches and what it counts of them, with CURSOR, the contact table's, as its first
guess. #P41RS7"
  (declare (type pair-sink sink) (type index cursor))
  (setf (pair-sink-count sink) 0 (pair-sink-cursor sink) cursor (pair-sink-misses sink) 0
        (pair-sink-fresh sink) 0 (pair-sink-first-row sink) -1 (pair-sink-new-count sink) 0)
  sink)

(defun pair-sink-grow (sink)
  "Give SINK room for twice its touches (at least 256), keeping them. #P41RS7"
  (declare (type pair-sink sink))
  (let* ((room (max 256 (* 2 (floor (length (pair-sink-touches sink)) 5))))
         (geometry (make-array (* 7 room) :element-type 'single-float :initial-element 0.0)))
    (setf (pair-sink-touches sink) (fixnum-room (pair-sink-touches sink) (* 5 room))
          (pair-sink-geometry sink) (replace geometry (pair-sink-geometry sink)))
    sink))

(declaim (inline pair-sink-touch))
(defun pair-sink-touch (sink contacts table key kind ha hb nx ny nz separation px py pz)
  "Write into SINK a touch of the contact of KIND under KEY, from handle HA to HB, with its
normal, separation and point: with the row under SINK's cursor when it holds KEY, else the row
CONTACTS' TABLE maps KEY to, or -1. Read CONTACTS and TABLE only. #P41RS7"
  (declare (type pair-sink sink) (type contact-columns contacts) (type contact-table table)
           (type fixnum key kind ha hb) (type single-float nx ny nz separation px py pz) #.+kernel-policy+)
  (let* ((guess (pair-sink-cursor sink))
         (row (if (and (< guess (contact-columns-length contacts))
                       (= (aref (contact-columns-key contacts) guess) key))
                  guess
                  (contact-table-find table key)))
         (k (pair-sink-count sink)))
    (declare (type fixnum row) (type index guess k))
    (if (>= row 0)
        (progn (unless (= guess row) (incf (pair-sink-misses sink)))
               (when (< (pair-sink-first-row sink) 0) (setf (pair-sink-first-row sink) row))
               (unless (= (aref (contact-columns-seen contacts) row) (contact-table-step table))
                 (incf (pair-sink-fresh sink)))
               (setf (pair-sink-cursor sink) (1+ row)))
        (let ((n (pair-sink-new-count sink)))
          (incf (pair-sink-misses sink))
          (when (>= n (length (pair-sink-new sink)))
            (setf (pair-sink-new sink) (fixnum-room (pair-sink-new sink) (1+ n))))
          (setf (aref (pair-sink-new sink) n) k (pair-sink-new-count sink) (1+ n))))
    (when (> (* 5 (1+ k)) (length (pair-sink-touches sink))) (pair-sink-grow sink))
    (let ((f (pair-sink-touches sink)) (g (pair-sink-geometry sink)) (o (* 5 k)) (q (* 7 k)))
      (declare (type index o q))
      (setf (aref f o) row (aref f (+ o 1)) key (aref f (+ o 2)) kind (aref f (+ o 3)) ha (aref f (+ o 4)) hb
            (aref g q) nx (aref g (+ q 1)) ny (aref g (+ q 2)) nz (aref g (+ q 3)) separation
            (aref g (+ q 4)) px (aref g (+ q 5)) py (aref g (+ q 6)) pz))
    (setf (pair-sink-count sink) (1+ k))
    sink))
;; Pairs: each awake pair once, and leaning on sleepers:4 ends here

;; [[file:../physics.org::#P41RS7][Pairs: each awake pair once, and leaning on sleepers:5]]
(declaim (inline pair-contact))
(defun pair-contact (contacts table overlaps margin slop dt gstep threshold impact
                     xi yi zi ri hi vxi vyi vzi xj yj zj rj hj vxj vyj vzj ci cj &optional sink)
  "Make or refresh the contact of two spheres (centres, radii, handles, velocities) when their
gap is under the speculative distance; with a SINK, a worker's pair sink ([[#P41P1C]]), write
the touch there instead. CI and CJ, the awake rows of a pair taken after
overlap-room, have its overlap counted in OVERLAPS; -1 for a pair not counted. Return, first,
true when the count made a row crowded; second, true when the pair strikes (closes faster than
THRESHOLD across a gap) and IMPACT is false: then it was counted but no contact was touched. #P41RS7"
  (declare (type contact-columns contacts) (type contact-table table) (type fixnum-column overlaps)
           (type single-float margin slop dt gstep threshold
                 xi yi zi ri xj yj zj rj vxi vyi vzi vxj vyj vzj)
           (type fixnum hi hj ci cj) #.+kernel-policy+ (inline touch-contact))
  (let* ((dx (- xj xi)) (dy (- yj yi)) (dz (- zj zi))
         (d2 (+ (* dx dx) (* dy dy) (* dz dz)))
         (reach (+ ri rj margin)))
    ;; only a pair within reach is counted: beyond it d2 - (ri + rj)^2 is not below
    ;; zero, so the count would add nothing, and every count at the bound has already
    ;; made its row crowded
    (if (< d2 (* reach reach))
      (let ((crowded nil))
        ;; the overlap is counted by the sign bit of d2 - (ri + rj)^2, not by a
        ;; branch: in a pile, half the pairs listed overlap, in no order a branch
        ;; predictor could learn
        (when (>= ci 0)
          (let ((bit (ldb (byte 1 31) (sb-kernel:single-float-bits (- d2 (* (+ ri rj) (+ ri rj)))))))
            (let ((oi (+ (aref overlaps ci) (if (> ri rj) 0 bit)))
                  (oj (+ (aref overlaps cj) (if (< ri rj) 0 bit))))
              (declare (type fixnum oi oj))
              (setf (aref overlaps ci) oi (aref overlaps cj) oj)
              ;; from the first crowded row on, every pair asks overlap-room
              (setf crowded (>= (logior oi oj) +overlaps-per-body+)))))
      (let ((d (fsqrt d2)))
       (multiple-value-bind (nx ny nz)
           (if (> d 1e-6)
               (let ((inv (/ 1.0 d))) (values (* dx inv) (* dy inv) (* dz inv)))
               (let ((cn (coincident-direction hi hj)))
                 (values (aref +unit-directions+ cn) (aref +unit-directions+ (+ cn 1))
                         (aref +unit-directions+ (+ cn 2)))))
        (declare (type single-float nx ny nz))
        (let ((sep (- d ri rj))
              (approach (+ (* (- vxi vxj) nx) (* (- vyi vyj) ny) (* (- vzi vzj) nz))))
        (declare (type single-float sep approach))
        (if (and (not impact) (> approach threshold) (> sep 0.0))
        (values crowded t)
        ;; a pair closing faster than the restitution threshold takes the normal of
        ;; the moment it will touch ([[#MYWH16]]): the line of centres then
        (multiple-value-bind (nx ny nz sep)
            (if (and impact (> approach threshold) (> sep 0.0))
                (pair-impact-normal dx dy dz (- vxj vxi) (- vyj vyi) (- vzj vzi) (+ ri rj) dt nx ny nz sep)
                (values nx ny nz sep))
          (declare (type single-float nx ny nz sep))
        (when (< sep (speculative-distance approach dt slop margin gstep))
          ;; orient every pair contact from the lower handle slot to the higher
          (multiple-value-bind (ha hb s px py pz)
              (if (< (handle-index hi) (handle-index hj))
                  (values hi hj 1.0 (+ xi (* ri nx)) (+ yi (* ri ny)) (+ zi (* ri nz)))
                  (values hj hi -1.0 (- xj (* rj nx)) (- yj (* rj ny)) (- zj (* rj nz))))
            (declare (type fixnum ha hb) (type single-float s px py pz))
            (if sink
                (pair-sink-touch sink contacts table (pair-key (handle-index ha) (handle-index hb))
                                 +contact-pair+ ha hb (* s nx) (* s ny) (* s nz) sep px py pz)
                (touch-contact contacts table (pair-key (handle-index ha) (handle-index hb))
                               +contact-pair+ ha hb (* s nx) (* s ny) (* s nz) sep px py pz
                               0.0 0.0 0.0))))
        (values crowded nil)))))))
      (values nil nil))))

(declaim (inline walk-listed-pairs))
(defun walk-listed-pairs (world start end crowded sink overlaps)
  "Take the listed pairs of WORLD's pair list from START below END whose rows both stayed, as the
pair phase takes them, counting overlaps in OVERLAPS, CROWDED telling whether some row is
crowded, but stop at a pair that strikes (pair-contact): return the place where the walk
stopped (END when it did not) and whether some row is crowded now. With a SINK the touches go
there (pair-contact). #P41RS7"
  (declare (type index start end) (type fixnum-column overlaps) #.+kernel-policy+)
  (with-world-parameters (margin slop (threshold restitution-threshold)) world
    (let* ((awake (physics-world-awake world))
           (plist (physics-world-pair-list world))
           (dt (physics-world-current-dt world))
           (gstep (gravity-step world dt))
           (contacts (physics-world-contacts world))
           (table (physics-world-contact-table world))
           (pairs (pair-list-pairs plist)) (loose (pair-list-loose plist)))
      (declare (type single-float margin slop dt gstep threshold) (type body-columns awake)
               (type pair-list plist) (type contact-columns contacts) (type contact-table table)
               (type fixnum-column pairs loose))
      (with-body-columns (x y z vx vy vz radius handle) awake
        (loop for p of-type index from start below end do
          (let* ((packed (aref pairs p)) (i (ash packed -24)) (j (logand packed #xFFFFFF)))
            (declare (type index i j))
            (when (and (zerop (logior (aref loose i) (aref loose j)))
                       (or (not crowded) (overlap-room overlaps i j radius)))
              (multiple-value-bind (full strikes)
                  (pair-contact contacts table overlaps margin slop dt gstep threshold nil
                                (aref x i) (aref y i) (aref z i) (aref radius i) (aref handle i)
                                (aref vx i) (aref vy i) (aref vz i)
                                (aref x j) (aref y j) (aref z j) (aref radius j) (aref handle j)
                                (aref vx j) (aref vy j) (aref vz j) i j sink)
                (when full (setf crowded t))
                (when strikes (return-from walk-listed-pairs (values p crowded)))))))
        (values end crowded)))))

(defun scan-listed-pairs (world start crowded)
  "Take the listed pairs of WORLD's pair list from START on (walk-listed-pairs), touching their
contacts: return where the walk stopped and whether some row is crowded now. A function of its
own, without the impact part, so that the walk keeps its values in registers. #P41RS7"
  (declare (type index start))
  (let ((plist (physics-world-pair-list world)))
    (walk-listed-pairs world start (pair-list-count plist) crowded nil (pair-list-overlaps plist))))
;; Pairs: each awake pair once, and leaning on sleepers:5 ends here

;; [[file:../physics.org::#P41HLD][The pairs of a list that holds:1]]
(defmacro pair-listed-pairs ()
  "The listed pairs whose rows both stayed (scan-listed-pairs), each pair that strikes taken
again whole, its overlap already counted: expanded in the pair phase while its list holds. #P41HLD"
  `(let ((p 0))
     (declare (type index p))
     (loop (multiple-value-setq (p crowded) (scan-listed-pairs world p crowded))
           (when (>= p (pair-list-count plist)) (return))
           (let* ((packed (aref pairs p)) (i (ash packed -24)) (j (logand packed #xFFFFFF)))
             (declare (type index i j))
             (pair (aref x i) (aref y i) (aref z i) (aref radius i) (aref handle i)
                   (aref vx i) (aref vy i) (aref vz i)
                   (aref x j) (aref y j) (aref z j) (aref radius j) (aref handle j)
                   (aref vx j) (aref vy j) (aref vz j) -1 -1))
           (incf p))))

(defmacro pair-loose-rows ()
  "Each loose row against the rows of its 27 cells that are not loose, in the awake grid:
expanded in the pair phase while its list holds. #P41HLD"
  `(dotimes (q strays)
     (let ((i (aref loose-rows q)) (refused 0))
       (declare (type index refused))
       (when (zerop (logand (aref flags i) +flag-terrain-only+))
         (block walk
           (do-grid-neighbours (j grid (aref x i) (aref y i) (aref z i))
             (when (and (zerop (aref loose j))
                        (zerop (logand (aref flags j) +flag-terrain-only+))
                        (rows-meet-p filtering (aref flags i) (aref flags j)))
               (rows i j (when (>= (incf refused) +overlaps-per-body+) (return-from walk))))))))))

(defmacro pair-loose-among-loose ()
  "Each pair of loose rows, from the lower row, in a grid of the loose rows alone: expanded in
the pair phase while its list holds. #P41HLD"
  `(when (> strays 1)
     (let ((lgrid (pair-list-loose-grid plist)) (lx (pair-list-loose-x plist))
           (ly (pair-list-loose-y plist)) (lz (pair-list-loose-z plist)))
       (declare (type f32-column lx ly lz))
       (dotimes (q strays)
         (let ((i (aref loose-rows q)))
           (setf (aref lx q) (aref x i) (aref ly q) (aref y i) (aref lz q) (aref z i))))
       ;; hashed: a dense box sized by the loose rows' spread could outgrow its room
       (build-hash-grid lgrid cell strays lx ly lz loose-rows :dense-allowed nil)
       (dotimes (q strays)
         (let ((i (aref loose-rows q)) (refused 0))
           (declare (type index refused))
           (when (zerop (logand (aref flags i) +flag-terrain-only+))
             (block walk
               (do-grid-neighbours (j lgrid (aref x i) (aref y i) (aref z i))
                 (when (and (> j i) (zerop (logand (aref flags j) +flag-terrain-only+))
                            (rows-meet-p filtering (aref flags i) (aref flags j)))
                   (rows i j (when (>= (incf refused) +overlaps-per-body+)
                               (return-from walk))))))))))))
;; The pairs of a list that holds:1 ends here

;; [[file:../physics.org::#P41BLD][Building the list again:1]]
(defmacro pair-list-walk ()
  "The walk of row I (at place E of the grid's order, its cell's half runs in RUNS) in the
build: take each row within the widest reach plus the skin, in order, and stop at the
+overlaps-per-body+th refusal. Expanded in pair-list-build. #P41BLD"
  `(let* ((widest (+ (aref radius i) rmax margin skin)) (reach2 (* widest widest))
          (refused 0))
     (declare (type single-float widest reach2) (type index refused))
     (block walk
       (flet ((take (found)
                ;; the FOUND places listed in NEAR, in order; the walk stops
                ;; at its +overlaps-per-body+th refusal
                (declare (type index found))
                (incf (pair-list-examined plist) found)
                (dotimes (q found)
                  (let ((j (aref items (aref near q))))
                    (when (and (zerop (logand (aref flags j) +flag-terrain-only+))
                               (rows-meet-p filtering (aref flags i) (aref flags j)))
                      (if (or (not crowded) (overlap-room (pair-list-overlaps plist) i j radius))
                          (progn (pair-list-push plist i j)
                                 (pair-of-rows i j))
                          (progn (setf crowd t)
                                 (when (>= (incf refused) +overlaps-per-body+)
                                   (return-from walk)))))))))
         (if (not crowd)
             (take (grid-list-near grid e runs run-count reach2 near))
             ;; once a walk of this build was refused, each run is listed a
             ;; chunk at a time, so a walk that stops lists little beyond it
             (dotimes (q run-count)
               (let ((end (aref runs (+ (* 3 q) 1))))
                 (loop for start of-type fixnum from (if (= q 0) (1+ e) (aref runs (* 3 q)))
                         below end by +crowded-walk-chunk+
                       do (setf (aref chunk 1) (1+ e) (aref chunk 2) -1
                                (aref chunk 3) start (aref chunk 4) (min end (+ start +crowded-walk-chunk+))
                                (aref chunk 5) (aref runs (+ (* 3 q) 2)))
                          (take (grid-list-near grid e chunk 2 reach2 near))))))))))

(defmacro pair-list-walks (from to near-form)
  "The walks of the bodies at places FROM below TO of the grid's order, listing their near places
in the column NEAR-FORM gives: expanded in pair-list-build, and in a worker's piece of it
([[#P41P1C]]). #P41BLD"
  `(let ((items (hash-grid-items grid)) (keys (hash-grid-keys grid)) (near ,near-form)
         (runs (make-array 42 :element-type 'fixnum))
         ;; a crowded walk's chunk: an empty first run, then a piece of one run
         (chunk (make-array 6 :element-type 'fixnum :initial-element 0))
         (cell-key -1) (run-count 0) (crowd nil))
     (declare (type fixnum-column items keys near runs chunk)
              (dynamic-extent runs chunk) (type fixnum cell-key) (type (integer 0 14) run-count))
     (loop for e of-type index from ,from below ,to
           do (let ((i (aref items e)))
                (when (zerop (logand (aref flags i) +flag-terrain-only+))
                  ;; the items of one cell are consecutive in the grid's order and share its runs
                  (unless (= (aref keys e) cell-key)
                    (setf cell-key (aref keys e) run-count (grid-half-runs grid e runs)))
                  (pair-list-walk))))))

(defmacro pair-list-build ()
  "Build the pair list again, taking each pair as it is found: the half neighbourhood of each
body's cell, in the grid's order, within the widest reach plus the skin; after a refused walk,
each run a chunk at a time; with workers, in pieces ([[#P41P1C]]). Expanded in the pair
phase. #P41BLD"
  `(progn
     (setf (pair-list-count plist) 0 (pair-list-examined plist) 0)
     (flet ((whole () (pair-list-walks 0 (hash-grid-count grid) (hash-grid-near grid))))
       (declare (dynamic-extent #'whole))
       (pairs-in-pieces world :build #'whole))
     (pair-list-anchor plist awake n cell)
     (setf (pair-list-built-step plist) (contact-table-step table)
           (pair-list-loose-count plist) 0)))
;; Building the list again:1 ends here

;; [[file:../physics.org::#P41LEN][Leaning on sleepers:1]]
(defmacro pair-leans-on-sleepers ()
  "Lean contacts: each awake body that meets bodies onto the sleepers within its reach, in the
order of their rows. Expanded in the pair phase. #P41LEN"
  `(when any-sleeping
     (dotimes (i n)
       (when (zerop (logand (aref flags i) +flag-terrain-only+))
         (let ((xi (aref x i)) (yi (aref y i)) (zi (aref z i)) (ri (aref radius i)) (hi (aref handle i))
               (vxi (aref vx i)) (vyi (aref vy i)) (vzi (aref vz i)))
           ;; the sleepers within reach, in the order of their rows: the lean contacts
           ;; are touched, and so ordered, as they would be from any grids
           (do-sleepers-in-row-order
               (h world xi yi zi)
               (let ((slot (handle-index h)))
                 (and (= (aref (handle-table-set ids) slot) +set-sleeping+)
                      (= (aref (handle-table-generation ids) slot) (handle-generation h))
                      (let ((row (aref (handle-table-local ids) slot)))
                        (and (zerop (logand (aref (body-columns-flags sleeping) row) +flag-terrain-only+))
                             (rows-meet-p filtering (aref flags i) (aref (body-columns-flags sleeping) row))
                             ;; pair-contact's own first test: a pair farther apart than
                             ;; this touches no contact
                             (let ((dx (- (aref (body-columns-x sleeping) row) xi))
                                   (dy (- (aref (body-columns-y sleeping) row) yi))
                                   (dz (- (aref (body-columns-z sleeping) row) zi))
                                   (reach (+ ri (aref (body-columns-radius sleeping) row) margin)))
                               (< (+ (* dx dx) (* dy dy) (* dz dz)) (* reach reach)))))))
             (let ((row (aref (handle-table-local ids) (handle-index h))))
               (pair xi yi zi ri hi vxi vyi vzi
                     (aref (body-columns-x sleeping) row) (aref (body-columns-y sleeping) row)
                     (aref (body-columns-z sleeping) row)
                     (aref (body-columns-radius sleeping) row) h 0.0 0.0 0.0 -1 -1))))))))
;; Leaning on sleepers:1 ends here

;; [[file:../physics.org::#P41STG][The pair phase, stage by stage:1]]
(defun pair-phase (world)
  "The pair phase: contacts between awake bodies (each pair once) and lean contacts from awake bodies
onto the sleepers they reach. The pairs come from the pair list while it still holds: the
listed pairs whose rows both stayed near their anchors, and for each loose row the awake
bodies of its 27 cells. Otherwise the list is built again, walking the half neighbourhood of
each body's cell in the grid's order. A candidate within reach becomes a contact only when its
gap is under the speculative distance. #P41STG"
  (with-world-parameters (margin (skin pair-skin) slop (rmax max-radius) (threshold restitution-threshold)) world
    (let* ((awake (physics-world-awake world))
           (sleeping (physics-world-sleeping world))
           (ids (physics-world-ids world))
           (grid (physics-world-awake-grid world))
           (plist (physics-world-pair-list world))
           (n (body-columns-length awake))
           (any-sleeping (plusp (body-columns-length sleeping)))
           (cell (f32 (grid-cell-size world)))
           (dt (physics-world-current-dt world))
           (gstep (gravity-step world dt))
           (contacts (physics-world-contacts world))
           (table (physics-world-contact-table world))
           ;; the grid phase counted the loose rows
           (strays (pair-list-loose-count plist))
           ;; true once a row has taken +overlaps-per-body+ overlapping pairs this step: until
           ;; then overlap-room is true of every pair and is not asked
           (crowded nil)
           ;; true once a body or box has a category or mask of its own ([[#F1LT3R]])
           (filtering (physics-world-filtering world)))
      (declare (type single-float margin skin cell slop dt gstep rmax threshold) (type index n) (type fixnum strays)
               (type body-columns awake sleeping) (type pair-list plist)
               (type contact-columns contacts) (type contact-table table)
               (type handle-table ids) (type hash-grid grid) #.+kernel-policy+
               (inline touch-contact))
      (with-body-columns (x y z vx vy vz radius flags handle) awake
        (flet ((pair (xi yi zi ri hi vxi vyi vzi xj yj zj rj hj vxj vyj vzj ci cj)
                 (declare (type single-float xi yi zi ri xj yj zj rj vxi vyi vzi vxj vyj vzj)
                          (type fixnum hi hj ci cj))
                 (when (pair-contact contacts table (pair-list-overlaps plist) margin slop dt gstep threshold t
                                     xi yi zi ri hi vxi vyi vzi xj yj zj rj hj vxj vyj vzj ci cj)
                   (setf crowded t))))
          (declare (inline pair))
          (pair-list-room plist n)
          (fill (pair-list-overlaps plist) 0 :end n)
          (macrolet ((pair-of-rows (i j)
                       ;; the pair of awake rows I and J
                       `(pair (aref x ,i) (aref y ,i) (aref z ,i) (aref radius ,i) (aref handle ,i)
                              (aref vx ,i) (aref vy ,i) (aref vz ,i)
                              (aref x ,j) (aref y ,j) (aref z ,j) (aref radius ,j) (aref handle ,j)
                              (aref vx ,j) (aref vy ,j) (aref vz ,j) ,i ,j))
                     (rows (i j &optional refused)
                       ;; the same, unless they overlap and the smaller has its share of
                       ;; overlaps: then REFUSED
                       `(if (or (not crowded) (overlap-room (pair-list-overlaps plist) ,i ,j radius))
                            (pair-of-rows ,i ,j)
                            ,refused)))
            (if (pair-list-holds-p strays n)
                ;; the list holds: its pairs whose rows both stayed; then each loose row against
                ;; the rows of its 27 cells that are not loose, in the awake grid, whose cells
                ;; may be the build's; then each pair of loose rows, from the lower row, in a
                ;; grid of the loose rows alone
                (let ((pairs (pair-list-pairs plist)) (loose (pair-list-loose plist))
                      (loose-rows (pair-list-loose-rows plist)))
                  (declare (type fixnum-column pairs loose loose-rows))
                  ;; the walk stops at a pair that strikes, which is taken here again whole,
                  ;; its overlap already counted; with workers, in pieces ([[#P41P1C]])
                  (flet ((whole () (pair-listed-pairs)))
                    (declare (dynamic-extent #'whole))
                    (pairs-in-pieces world :listed #'whole))
                  (pair-loose-rows)
                  (pair-loose-among-loose))
                ;; build the list again: the half neighbourhood of each body's cell, in the
                ;; grid's order, within the widest reach plus the skin
                (pair-list-build)))
          (setf (pair-list-step plist) (contact-table-step table))
          ;; slow or fast, an awake body reaching a sleeper leans on it
          (pair-leans-on-sleepers)))
      world)))
;; The pair phase, stage by stage:1 ends here

;; [[file:../physics.org::#MYWH16][Sphere against cells: the overshoot rule keeps seams smooth:1]]
(defmacro with-cell-closest-point ((nx ny nz px py pz separation d2 ox oy oz)
                                   (cx cy cz r minx miny minz maxx maxy maxz) outside inside)
  "Bind the closest point of box MIN..MAX to centre C. When C is outside the box, run OUTSIDE with
the overshoot signs OX OY OZ, the squared distance D2 and the point; NX..SEPARATION are
computed lazily by OUTSIDE itself through the local function FINISH. When C is inside, run
INSIDE. #MYWH16"
  `(let* ((,px (max ,minx (min ,maxx ,cx)))
          (,py (max ,miny (min ,maxy ,cy)))
          (,pz (max ,minz (min ,maxz ,cz)))
          (,ox (cond ((< ,cx ,minx) -1) ((> ,cx ,maxx) 1) (t 0)))
          (,oy (cond ((< ,cy ,miny) -1) ((> ,cy ,maxy) 1) (t 0)))
          (,oz (cond ((< ,cz ,minz) -1) ((> ,cz ,maxz) 1) (t 0)))
          (,d2 (+ (* (- ,px ,cx) (- ,px ,cx)) (* (- ,py ,cy) (- ,py ,cy)) (* (- ,pz ,cz) (- ,pz ,cz)))))
     (declare (type single-float ,px ,py ,pz ,d2) (type (integer -1 1) ,ox ,oy ,oz))
     (if (or (/= ,ox 0) (/= ,oy 0) (/= ,oz 0))
         (flet ((finish ()
                  (let* ((d (fsqrt ,d2)) (inv (/ 1.0 (max d 1e-12))))
                    (values (* (- ,px ,cx) inv) (* (- ,py ,cy) inv) (* (- ,pz ,cz) inv) (- d ,r)))))
           (declare (inline finish) (ignorable #'finish))
           ,outside)
         (let ((,nx 0.0) (,ny 0.0) (,nz 0.0) (,separation 0.0))
           (declare (ignorable ,nx ,ny ,nz ,separation))
           ,inside))))

(declaim (inline step-travel step-reach))
(defun step-travel (vx vy vz dt gstep)
  "How far a body moving at VX VY VZ, relative to what it may meet, can travel in a step of DT
seconds in which gravity adds GSTEP to its speed. #MYWH16"
  (declare (type single-float vx vy vz dt gstep))
  (* dt (+ gstep (fsqrt (+ (* vx vx) (* vy vy) (* vz vz))))))

(defun step-reach (r travel margin limit)
  "How far from its centre a body of radius R that can TRAVEL this far looks for contacts: its
radius plus the larger of the margin and its travel, at most LIMIT. The terrain and box phases
gather within it; the finalize phase checks a path longer than it less the radius ([[#SQU33Z]]). #MYWH16"
  (declare (type single-float r travel margin limit))
  (min limit (+ r (max margin travel))))

(declaim (inline impact-normal))
(defun impact-normal (nx ny nz separation cx cy cz r vx vy vz dt threshold minx miny minz maxx maxy maxz)
  "The normal and separation of the contact between the box MIN..MAX and a sphere of radius R at
CX CY CZ moving at VX VY VZ, whose closest point gives NX NY NZ and SEPARATION: when the sphere
approaches faster than THRESHOLD, the normal at the point it will strike within DT (advanced
three times along its path), and its gap along that normal. #MYWH16"
  (declare (type single-float nx ny nz separation cx cy cz r vx vy vz dt threshold minx miny minz maxx maxy maxz))
  (let ((approach (+ (* vx nx) (* vy ny) (* vz nz))))
    (declare (type single-float approach threshold))
    (if (or (<= approach threshold) (<= separation 0.0))
        (values nx ny nz separation)
        (let ((time 0.0) (mx nx) (my ny) (mz nz) (gap separation))
          (declare (type single-float time mx my mz gap))
          ;; conservative advancement: move along the path by the gap over the approach
          ;; speed along the current normal, and take the closest point again from there
          (dotimes (k 3)
            (let ((closing (+ (* vx mx) (* vy my) (* vz mz))))
              (declare (type single-float closing))
              (when (and (> closing 0.0) (> gap 0.0))
                (setf time (min dt (+ time (/ gap closing))))
                (let* ((qx (+ cx (* vx time))) (qy (+ cy (* vy time))) (qz (+ cz (* vz time)))
                       (px (max minx (min maxx qx))) (py (max miny (min maxy qy))) (pz (max minz (min maxz qz)))
                       (ex (- px qx)) (ey (- py qy)) (ez (- pz qz))
                       (d (fsqrt (+ (* ex ex) (* ey ey) (* ez ez)))))
                  (declare (type single-float qx qy qz px py pz ex ey ez d))
                  (when (> d 1e-6)
                    (setf mx (/ ex d) my (/ ey d) mz (/ ez d)
                          gap (- d r)))))))
          ;; the gap along the new normal from where the sphere is now
          (let ((px (max minx (min maxx (+ cx (* vx time)))))
                (py (max miny (min maxy (+ cy (* vy time)))))
                (pz (max minz (min maxz (+ cz (* vz time))))))
            (values mx my mz (- (+ (* (- px cx) mx) (* (- py cy) my) (* (- pz cz) mz)) r)))))))

(defun inside-face (probe cx cy cz r minx miny minz maxx maxy maxz ix iy iz)
  "For a centre CX CY CZ inside the box MIN..MAX: the face to push it out through, as normal,
point and separation. With a PROBE, the box is cell IX IY IZ and the shallowest face whose
neighbour cell is air wins over the shallowest; without one (a posted box) every face is
open. #MYWH16"
  (declare (type single-float cx cy cz r minx miny minz maxx maxy maxz) (type cell ix iy iz))
  (let ((best-depth most-positive-single-float) (best 0) (best-open nil))
    (declare (type single-float best-depth) (type (integer 0 5) best))
    (dotimes (f 6)
      (let ((depth (case f (0 (- cx minx)) (1 (- maxx cx)) (2 (- cy miny))
                         (3 (- maxy cy)) (4 (- cz minz)) (t (- maxz cz))))
            (open (or (null probe)
                      (not (probe-solid-p probe
                                          (+ ix (case f (0 -1) (1 1) (t 0)))
                                          (+ iy (case f (2 -1) (3 1) (t 0)))
                                          (+ iz (case f (4 -1) (5 1) (t 0))))))))
        (declare (type single-float depth))
        (when (or (and open (not best-open))
                  (and (eq open best-open) (< depth best-depth)))
          (setf best f best-depth depth best-open open))))
    (let ((fx (case best (0 -1.0) (1 1.0) (t 0.0)))
          (fy (case best (2 -1.0) (3 1.0) (t 0.0)))
          (fz (case best (4 -1.0) (5 1.0) (t 0.0))))
      (values (- fx) (- fy) (- fz)
              (+ cx (* best-depth fx)) (+ cy (* best-depth fy)) (+ cz (* best-depth fz))
              (- (+ best-depth r))))))

(declaim (type (simple-array (unsigned-byte 27) (8)) +span-masks+))
(sb-ext:defglobal +span-masks+
  (let ((masks (make-array 8 :element-type '(unsigned-byte 27) :initial-element 0)))
    (dotimes (span 8 masks)
      (dotimes (dz 2)
        (dotimes (dy 2)
          (dotimes (dx 2)
            (when (and (<= dx (ldb (byte 1 0) span)) (<= dy (ldb (byte 1 1) span)) (<= dz (ldb (byte 1 2) span)))
              (setf (ldb (byte 1 (+ dx (* 3 dy) (* 9 dz))) (aref masks span)) 1)))))))
  "For a span of one or two cells along x, y and z (bits 0, 1 and 2 of the index set for two),
the bits of the 27-bit neighbourhood mask that lie inside it. #MYWH16")
;; Sphere against cells: the overshoot rule keeps seams smooth:1 ends here

;; [[file:../physics.org::#MYWGTH][Gathering the cells:1]]
(defmacro terrain-block-mask ()
  "The solid cells of row I's span X0..X1, Y0..Y1, Z0..Z1 (at most two cells a side, a 2x2x2
block in one chunk) as the bits of its 27-bit mask: eight reads at fixed offsets, no loop, then
only the cells in the span kept. Expanded in terrain-gather-mask. #MYWGTH"
  `(let ((chunk (chunk-at (chunk-key x0 y0 z0)))
         (o (cell-offset x0 y0 z0)))
     (declare (type chunk-storage chunk) (type (integer 0 4095) o))
     (flet ((solid-bit (offset bit)
              (declare (type (integer 0 4095) offset) (type (integer 0 13) bit))
              ;; a cell's byte plus 255, shifted right eight places: 1 when solid
              (ash (ash (+ (aref chunk offset) 255) -8) bit)))
       (declare (inline solid-bit))
       (let ((sx 1) (sz (ash 1 +chunk-bits+)) (sy (ash 1 (* 2 +chunk-bits+))))
         (setf mask (logand (aref +span-masks+ (+ (- x1 x0) (* 2 (- y1 y0)) (* 4 (- z1 z0))))
                            (logior (solid-bit o 0) (solid-bit (+ o sx) 1)
                                    (solid-bit (+ o sy) 3) (solid-bit (+ o sx sy) 4)
                                    (solid-bit (+ o sz) 9) (solid-bit (+ o sx sz) 10)
                                    (solid-bit (+ o sy sz) 12) (solid-bit (+ o sx sy sz) 13))))))))

(defmacro terrain-gather-mask ()
  "Set MASK to the solid cells of the (at most) 3x3x3 neighbourhood X0..X1, Y0..Y1, Z0..Z1 of
row I, unless the row stayed near its anchor and the anchor had no solid cell near it: expanded
in the terrain phase. #MYWGTH"
  `(unless (and use-clear (zerop (aref loose i)) (= (aref clear i) 1))
   (cond
     ;; the common case, at most two cells a side and a 2x2x2 block in one chunk:
     ;; eight reads at fixed offsets, no loop, then only the cells in the span kept
     ((and (<= (- x1 x0) 1) (<= (- y1 y0) 1) (<= (- z1 z0) 1)
           (= (ash x0 (- +chunk-bits+)) (ash (1+ x0) (- +chunk-bits+)))
           (= (ash y0 (- +chunk-bits+)) (ash (1+ y0) (- +chunk-bits+)))
           (= (ash z0 (- +chunk-bits+)) (ash (1+ z0) (- +chunk-bits+))))
      (terrain-block-mask))
     ;; otherwise cell by cell, each through the chunk it lies in
     (t
       (loop for iz of-type fixnum from z0 to z1 do
         (loop for iy of-type fixnum from y0 to y1 do
           (loop for ix of-type fixnum from x0 to x1 do
             (when (cell-solid-p ix iy iz)
               (setf mask (logior mask (ash 1 (the (integer 0 26) (+ (- ix x0) (* 3 (- iy y0)) (* 9 (- iz z0)))))))))))))))

(defmacro terrain-note-clear ()
  "In the step that built the pair list, note in CLEAR whether every cell within row I's reach
plus 0.45 skins is air: expanded in the terrain phase. #MYWGTH"
  `(when fresh
     (setf (aref clear i)
           (if (and (zerop mask)
                    (let ((wide (+ reach widen)))
                      (loop for iz of-type fixnum from (cell-floor (- cz wide)) to (cell-floor (+ cz wide))
                            always (loop for iy of-type fixnum from (cell-floor (- cy wide)) to (cell-floor (+ cy wide))
                                         always (loop for ix of-type fixnum from (cell-floor (- cx wide))
                                                        to (cell-floor (+ cx wide))
                                                      never (cell-solid-p ix iy iz))))))
               1 0))))
;; Gathering the cells:1 ends here

;; [[file:../physics.org::#MYWCNT][A contact per cell:1]]
(defmacro terrain-outside-contact ()
  "Row I's contact with the solid cell IX IY IZ whose closest point lies outside the body: the
overshoot rule, the nearest solid cell so far, a fast approach's impact normal, then the contact
when its gap is under the speculative distance. Expanded in terrain-cell-contacts. #MYWCNT"
  `(when (and (<= d2 (* reach reach))
              (not (or (and (/= ox 0) (solid (+ ix ox) iy iz))
                       (and (/= oy 0) (solid ix (+ iy oy) iz))
                       (and (/= oz 0) (solid ix iy (+ iz oz)))
                       (and (/= ox 0) (/= oy 0) (solid (+ ix ox) (+ iy oy) iz))
                       (and (/= ox 0) (/= oz 0) (solid (+ ix ox) iy (+ iz oz)))
                       (and (/= oy 0) (/= oz 0) (solid ix (+ iy oy) (+ iz oz)))
                       (and (/= ox 0) (/= oy 0) (/= oz 0)
                            (solid (+ ix ox) (+ iy oy) (+ iz oz))))))
     (when (< d2 (aref near i)) (setf (aref near i) d2))
     (multiple-value-bind (nx ny nz sep)
         (multiple-value-bind (nx ny nz sep) (finish)
           ;; a fast approach strikes the cell joined with its solid face
           ;; neighbours, which read through the chunk: they may lie
           ;; outside the gathered span
           (if (and (> (+ (* (aref vx i) nx) (* (aref vy i) ny) (* (aref vz i) nz)) threshold)
                    (> sep 0.0))
               (impact-normal nx ny nz sep cx cy cz r (aref vx i) (aref vy i) (aref vz i) dt
                              threshold
                              (if (cell-solid-p (- ix 1) iy iz) (- fx 1.0) fx)
                              (if (cell-solid-p ix (- iy 1) iz) (- fy 1.0) fy)
                              (if (cell-solid-p ix iy (- iz 1)) (- fz 1.0) fz)
                              (if (cell-solid-p (+ ix 1) iy iz) (+ fx 2.0) (+ fx 1.0))
                              (if (cell-solid-p ix (+ iy 1) iz) (+ fy 2.0) (+ fy 1.0))
                              (if (cell-solid-p ix iy (+ iz 1)) (+ fz 2.0) (+ fz 1.0)))
               (values nx ny nz sep)))
       (when (< sep (speculative-distance
                     (+ (* (aref vx i) nx) (* (aref vy i) ny) (* (aref vz i) nz))
                     dt slop ahead gstep))
         (if sink
             (pair-sink-touch sink contacts table key +contact-terrain+ (aref handle i) +no-body+
                              nx ny nz sep px py pz)
             (touch-contact contacts table key +contact-terrain+ (aref handle i) +no-body+
                            nx ny nz sep px py pz 0.0 0.0 0.0))))))

(defmacro terrain-inside-contact ()
  "Row I's contact with the solid cell IX IY IZ that holds its centre: pushed out through a
face (inside-face), and the body counted buried. Expanded in terrain-cell-contacts. #MYWCNT"
  `(progn
     (setf (aref near i) 0.0)
     (incf buried)
     (multiple-value-bind (nx ny nz px py pz sep)
         (inside-face probe cx cy cz r fx fy fz (+ fx 1.0) (+ fy 1.0) (+ fz 1.0)
                      ix iy iz)
       (if sink
           (pair-sink-touch sink contacts table key +contact-terrain+ (aref handle i) +no-body+
                            nx ny nz sep px py pz)
           (touch-contact contacts table key +contact-terrain+ (aref handle i) +no-body+
                          nx ny nz sep px py pz 0.0 0.0 0.0)))))

(defmacro span-cell-contacts (solid)
  "Offer a contact for each cell of row I's span X0..X1, Y0..Y1, Z0..Z1 that the form SOLID, read
with IX IY IZ the cell, calls solid; SOLID also answers the overshoot rule's question about a
neighbour. Expanded by terrain-cell-contacts and terrain-large-contacts. #MYWCNT"
  `(flet ((solid (ix iy iz)
            (declare (type fixnum ix iy iz))
            ,solid))
     (declare (inline solid))
     (loop for iz of-type fixnum from z0 to z1 do
       (loop for iy of-type fixnum from y0 to y1 do
         (loop for ix of-type fixnum from x0 to x1 do
           (when (solid ix iy iz)
             (let ((fx (float ix 1.0)) (fy (float iy 1.0)) (fz (float iz 1.0))
                   (key (terrain-key (handle-index (aref handle i)) ix iy iz)))
               (with-cell-closest-point (nx ny nz px py pz sep d2 ox oy oz)
                   (cx cy cz r fx fy fz (+ fx 1.0) (+ fy 1.0) (+ fz 1.0))
                 ;; outside: the overshoot rule, the nearest solid cell so far, then
                 ;; the contact. A cell the rule silences has a solid cell nearer
                 ;; the centre, so the nearest is among those it keeps
                 (terrain-outside-contact)
                 ;; inside: push out through a face, and count the body buried
                 (terrain-inside-contact)))))))))

(defmacro terrain-cell-contacts ()
  "Offer a contact for each solid cell of row I's MASK: expanded in the terrain phase. #MYWCNT"
  `(unless (zerop mask)
     (span-cell-contacts (logbitp (+ (- ix x0) (* 3 (- iy y0)) (* 9 (- iz z0))) mask))))
;; A contact per cell:1 ends here

;; [[file:../physics.org::#B1GBDY][Bodies larger than a cell:1]]
(declaim (inline large-step-reach body-reach))
(defun large-step-reach (r travel margin limit)
  "How far from its centre a body larger than a cell (radius over LIMIT less MARGIN) looks for
contacts: its radius plus the larger of the margin and its travel, the travel counted up to LIMIT
(the sweep looks along the rest of its path). #B1GBDY"
  (declare (type single-float r travel margin limit))
  (+ r (min limit (max margin travel))))

(defun body-reach (r travel margin limit)
  "How far from its centre a body of radius R looks for contacts: step-reach when its reach stays
under LIMIT, large-step-reach for a larger body. #B1GBDY"
  (declare (type single-float r travel margin limit))
  (if (> r (- limit margin))
      (large-step-reach r travel margin limit)
      (step-reach r travel margin limit)))

(defmacro terrain-large-contacts ()
  "Offer a contact for each solid cell of row I's span X0..X1, Y0..Y1, Z0..Z1, read cell by cell
through its chunk: the contacts of terrain-cell-contacts, the overshoot rule asking the cells
themselves. Expanded in terrain-large-row. #B1GBDY"
  `(span-cell-contacts (cell-solid-p ix iy iz)))

(defmacro terrain-large-row ()
  "Row I's contacts with the cells, for a body whose reach passes the reach limit: its reach
(large-step-reach), the path check's bound, its sweep, and a contact per solid cell of its span,
read one by one. Expanded in terrain-rows, whose variables it reads. #B1GBDY"
  `(let* ((cx (aref x i)) (cy (aref y i)) (cz (aref z i)) (r (aref radius i))
          (travel (step-travel (aref vx i) (aref vy i) (aref vz i) dt gstep))
          (ahead (max margin travel))
          (reach (large-step-reach r travel margin limit))
          (x0 (cell-floor (- cx reach))) (x1 (cell-floor (+ cx reach)))
          (y0 (cell-floor (- cy reach))) (y1 (cell-floor (+ cy reach)))
          (z0 (cell-floor (- cz reach))) (z1 (cell-floor (+ cz reach))))
     (declare (type fixnum x0 x1 y0 y1 z0 z1) (ignorable ahead))
     ;; never skipped: a large row has no mask to skip
     (when fresh (setf (aref clear i) 0))
     (setf (aref near i) (let ((looked (- reach r))) (* looked looked)))
     (unless (and boxes (logtest (aref flags i) +flag-box-shape+))
       (when (> travel margin)
         (sweep-terrain-contact contacts table probe (aref handle i) cx cy cz r
                                (aref vx i) (aref vy i) (aref vz i) (+ travel r) sink))
       (terrain-large-contacts))))
;; Bodies larger than a cell:1 ends here

;; [[file:../physics.org::#MYWSTG][The terrain phase, stage by stage:1]]
(defmacro terrain-small-row ()
  "Row I's contacts with the cells, for a body whose reach stays under the reach limit: its
reach, the mask of its cells, the path check's bound, its sweep, and a contact per cell.
Expanded in terrain-rows, whose variables it reads. #MYWSTG"
  `(let* ((cx (aref x i)) (cy (aref y i)) (cz (aref z i)) (r (aref radius i))
          ;; how far the body can travel this step; a body faster than its margin a
          ;; step reaches that far, so that it meets an edge or a corner before it strikes
          (travel (step-travel (aref vx i) (aref vy i) (aref vz i) dt gstep))
          (ahead (max margin travel))
          (reach (step-reach r travel margin limit))
          (x0 (cell-floor (- cx reach))) (x1 (cell-floor (+ cx reach)))
          (y0 (cell-floor (- cy reach))) (y1 (cell-floor (+ cy reach)))
          (z0 (cell-floor (- cz reach))) (z1 (cell-floor (+ cz reach)))
          (mask 0))
     (declare (type fixnum x0 x1 y0 y1 z0 z1) (type (unsigned-byte 27) mask))
     ;; gather the solid cells of the (at most) 3x3x3 neighbourhood, unless the row
     ;; stayed near its anchor and the anchor had no solid cell near it
     (terrain-gather-mask)
     ;; in the step that built the pair list, each row's anchor is its centre: note
     ;; whether every cell within its reach plus 0.45 skins is air
     (terrain-note-clear)
     ;; as far as the cells gathered reach, until a solid one nearer is met below
     (setf (aref near i) (let ((looked (- reach r))) (* looked looked)))
     ;; a box's points are its own ([[#BXCELL]]), found when the world has boxes
     (unless (and boxes (logtest (aref flags i) +flag-box-shape+))
       ;; a body that can travel past its margin this step also sweeps its path
       (when (> travel margin)
         (sweep-terrain-contact contacts table probe (aref handle i) cx cy cz r
                                (aref vx i) (aref vy i) (aref vz i) (+ travel r) sink))
       (terrain-cell-contacts))))

(declaim (inline terrain-rows))
(defun terrain-rows (world from to sink probe)
  "The terrain phase's awake rows FROM below TO, their chunks read through PROBE, their touches
into SINK when one is given: return how many of them lie buried. #MYWSTG"
  (declare (type index from to) (type terrain-probe probe) #.+kernel-policy+)
  (let ((terrain (physics-world-terrain world)))
      (with-world-parameters (margin slop (limit reach-limit) (threshold restitution-threshold)) world
        (let* ((awake (physics-world-awake world))
               (dt (physics-world-current-dt world))
               (gstep (gravity-step world dt))
               (contacts (physics-world-contacts world))
               (table (physics-world-contact-table world))
               ;; the bodies come in the grid's order, so most share the chunk of the one before
               (last-key -1) (last-chunk nil)
               ;; the pair list's rows this step: which are loose, and which were clear of
               ;; solid cells around their anchors when it was built
               (plist (physics-world-pair-list world))
               (current (= (pair-list-step plist) (contact-table-step table)))
               (fresh (and current (= (pair-list-built-step plist) (contact-table-step table))))
               (use-clear (and current (not fresh) (eq (pair-list-terrain plist) terrain)
                               (= (pair-list-terrain-edits plist) (voxel-terrain-edits terrain))))
               (loose (pair-list-loose plist)) (clear (pair-list-clear plist))
               (widen (* 0.45 (f32 (physics-world-pair-skin world))))
               (near (physics-world-near-cells world))
               ;; the bodies whose centre lies in a solid cell
               (buried 0)
               (boxes (physics-world-box-bodies world)))
          (declare (type single-float margin limit threshold slop dt gstep widen) (type fixnum last-key buried)
                   (type (or null chunk-storage) last-chunk) (type fixnum-column loose clear) (type f32-column near)
                   (type contact-columns contacts) (type contact-table table) (inline touch-contact))
          (labels ((chunk-at (key)
                     (declare (type fixnum key))
                     (if (= key last-key)
                         (the chunk-storage last-chunk)
                         (setf last-key key last-chunk (probe-chunk probe key))))
                   (cell-solid-p (ix iy iz)
                     ;; one cell, through the chunk it lies in
                     (declare (type fixnum ix iy iz))
                     (plusp (aref (the chunk-storage (chunk-at (chunk-key ix iy iz))) (cell-offset ix iy iz)))))
            (declare (inline chunk-at cell-solid-p))
          (with-body-columns (x y z vx vy vz radius handle flags) awake
            ;; a world that has never had a body larger than a cell walks its rows as it
            ;; always did; one that has tests each row's radius ([[#B1GBDY]])
            (if (> (f32 (physics-world-max-radius world)) (- limit margin))
                (loop for i of-type index from from below to do
                  (if (> (aref radius i) (- limit margin)) (terrain-large-row) (terrain-small-row)))
                (loop for i of-type index from from below to do (terrain-small-row)))))
          buried))))

(defun terrain-phase (world)
  "The terrain phase: each awake body gathers the solid cells within its reach into a 27-bit mask and
offers one contact per cell whose face, edge or corner passes the overshoot rule and whose gap
is under the speculative distance; with workers, its rows in pieces ([[#MYWP1C]]). #MYWSTG"
  (let ((terrain (physics-world-terrain world)))
    (when terrain
      (let* ((n (body-columns-length (physics-world-awake world)))
             (table (physics-world-contact-table world))
             (plist (physics-world-pair-list world)))
        ;; in the step that built the pair list, the clear marks are noted for this terrain
        (when (and (= (pair-list-step plist) (contact-table-step table))
                   (= (pair-list-built-step plist) (contact-table-step table)))
          (setf (pair-list-terrain plist) terrain (pair-list-terrain-edits plist) (voxel-terrain-edits terrain)))
        ;; for each row, the square of the longest path the finalize phase may leave
        ;; unchecked ([[#SQU33Z]]): as far as its reach, and short of the nearest solid cell
        (unless (> (length (physics-world-near-cells world)) n)
          (setf (physics-world-near-cells world) (make-array (* 2 (1+ n)) :element-type 'single-float)))
        (setf (physics-world-near-cells-step world) (contact-table-step table))
        (flet ((whole () (terrain-rows world 0 n nil (physics-world-probe world))))
          (declare (dynamic-extent #'whole))
          (setf (physics-world-buried-count world) (terrain-in-pieces world #'whole))))))
  world)
;; The terrain phase, stage by stage:1 ends here

;; [[file:../physics.org::#SW33P7][Fast bodies sweep their path through the cells:1]]
(declaim (inline first-solid-on-ray))
(defun first-solid-on-ray (probe cx cy cz dx dy dz length)
  "Walk the cells along the ray from CX CY CZ in the unit direction DX DY DZ for LENGTH metres
(Amanatides-Woo). Return the axis (0, 1, 2) of the face through which the ray enters the first
solid cell, the distance along the ray to that face and the cell IX IY IZ; or -1 when the ray
starts in a solid cell or meets none within LENGTH. #SW33P7"
  (declare (type single-float cx cy cz dx dy dz length) #.+kernel-policy+)
  (let* ((ix (cell-floor cx)) (iy (cell-floor cy)) (iz (cell-floor cz))
         (sx (if (> dx 0.0) 1 -1)) (sy (if (> dy 0.0) 1 -1)) (sz (if (> dz 0.0) 1 -1))
         (big 1e30))
    (declare (type single-float big) (type fixnum ix iy iz sx sy sz))
    (flet ((first-crossing (c i d s)
             (declare (type single-float c d) (type fixnum i s))
             (if (< (abs d) 1e-12) big (/ (- (float (if (> s 0) (1+ i) i) 1.0) c) d)))
           (per-cell (d) (declare (type single-float d)) (if (< (abs d) 1e-12) big (/ 1.0 (abs d)))))
      (let ((tx (first-crossing cx ix dx sx)) (ty (first-crossing cy iy dy sy)) (tz (first-crossing cz iz dz sz))
            (ex (per-cell dx)) (ey (per-cell dy)) (ez (per-cell dz)))
        (declare (type single-float tx ty tz ex ey ez))
        (if (probe-solid-p probe ix iy iz)
            (values -1 0.0 ix iy iz)
            (loop repeat 4096
                  do (let ((axis (cond ((and (<= tx ty) (<= tx tz)) 0) ((<= ty tz) 1) (t 2))))
                       (declare (type (integer 0 2) axis))
                       (let ((at (case axis (0 tx) (1 ty) (t tz))))
                         (declare (type single-float at))
                         (when (> at length) (return (values -1 0.0 ix iy iz)))
                         (case axis
                           (0 (incf ix sx) (incf tx ex))
                           (1 (incf iy sy) (incf ty ey))
                           (t (incf iz sz) (incf tz ez)))
                         (when (probe-solid-p probe ix iy iz)
                           (return (values axis at ix iy iz)))))
                  finally (return (values -1 0.0 ix iy iz))))))))

(defun sweep-terrain-contact (contacts table probe handle cx cy cz r vx vy vz length &optional sink)
  "Walk the cells along the ray from CX CY CZ in the direction of VX VY VZ for LENGTH metres;
at the first solid cell, make HANDLE's body a speculative contact, in CONTACTS and TABLE,
with the face the ray enters it through; or write the touch into SINK, a worker's pair sink
([[#P41P1C]]). #SW33P7"
  (declare (type contact-columns contacts) (type contact-table table)
           (type single-float cx cy cz r vx vy vz length) (type fixnum handle) #.+kernel-policy+)
  (let* ((speed (fsqrt (+ (* vx vx) (* vy vy) (* vz vz))))
         (inv (/ 1.0 (max speed 1e-12)))
         (dx (* vx inv)) (dy (* vy inv)) (dz (* vz inv)))
    (declare (type single-float speed inv dx dy dz))
    (multiple-value-bind (axis at ix iy iz) (first-solid-on-ray probe cx cy cz dx dy dz length)
      (declare (type (integer -1 2) axis) (ignore at) (type fixnum ix iy iz))
      (unless (< axis 0)
        ;; the face entered: its plane, the normal towards the cell
        (let ((sx (if (> dx 0.0) 1 -1)) (sy (if (> dy 0.0) 1 -1)) (sz (if (> dz 0.0) 1 -1)))
          (declare (type fixnum sx sy sz))
          (multiple-value-bind (nx ny nz gap)
              (case axis
                (0 (values (float sx 1.0) 0.0 0.0
                           (* (float sx 1.0) (- (float (if (> sx 0) ix (1+ ix)) 1.0) cx))))
                (1 (values 0.0 (float sy 1.0) 0.0
                           (* (float sy 1.0) (- (float (if (> sy 0) iy (1+ iy)) 1.0) cy))))
                (t (values 0.0 0.0 (float sz 1.0)
                           (* (float sz 1.0) (- (float (if (> sz 0) iz (1+ iz)) 1.0) cz)))))
            (declare (type single-float nx ny nz gap))
            (if sink
                (pair-sink-touch sink contacts table (terrain-key (handle-index handle) ix iy iz) +contact-terrain+
                                 handle +no-body+ nx ny nz (- gap r)
                                 (+ cx (* gap nx)) (+ cy (* gap ny)) (+ cz (* gap nz)))
                (touch-contact contacts table (terrain-key (handle-index handle) ix iy iz) +contact-terrain+
                               handle +no-body+ nx ny nz (- gap r)
                               (+ cx (* gap nx)) (+ cy (* gap ny)) (+ cz (* gap nz)) 0.0 0.0 0.0))))))))
;; Fast bodies sweep their path through the cells:1 ends here

;; [[file:../physics.org::#B0XPH5][Boxes touch as moving terrain:1]]
(defun box-phase (world)
  "The box phase: posted kinematic boxes touch the awake bodies near them as moving terrain. #B0XPH5"
  (with-world-parameters (margin (limit reach-limit) (threshold restitution-threshold)) world
    (let* ((boxes (physics-world-boxes world))
           (awake (physics-world-awake world))
           (grid (physics-world-awake-grid world))
           (dt (physics-world-current-dt world))
           (gstep (gravity-step world dt))
           (contacts (physics-world-contacts world))
           (table (physics-world-contact-table world))
           (touched nil)
           ;; true once a body or box has a category or mask of its own ([[#F1LT3R]])
           (filtering (physics-world-filtering world)))
      (declare (type single-float margin limit dt gstep threshold))
      (when (plusp (box-columns-length boxes))
        (with-body-columns (x y z (bvx vx) (bvy vy) (bvz vz) radius handle flags) awake
          (with-box-columns (min-x min-y min-z max-x max-y max-z vx vy vz id filter) boxes
            (dotimes (b (box-columns-length boxes))
              (let* ((bx0 (aref min-x b)) (by0 (aref min-y b)) (bz0 (aref min-z b))
                     (bx1 (aref max-x b)) (by1 (aref max-y b)) (bz1 (aref max-z b))
                     (ccx (* 0.5 (+ bx0 bx1))) (ccy (* 0.5 (+ by0 by1))) (ccz (* 0.5 (+ bz0 bz1)))
                     (half (max (- bx1 ccx) (- by1 ccy) (- bz1 ccz)))
                     (span (1+ (ceiling (* half (hash-grid-inv-cell grid))))))
                (do-grid-neighbours (i grid ccx ccy ccz :span span)
                 (when (and (rows-meet-p filtering (aref flags i) (ash (aref filter b) +flag-filter-shift+))
                            ;; a box body meets a posted box through its own points ([[#BXPUSH]])
                            (not (logtest (aref flags i) +flag-box-shape+)))
                  (let* ((cx (aref x i)) (cy (aref y i)) (cz (aref z i)) (r (aref radius i))
                         ;; the body's velocity relative to the box, and how far it can travel
                         ;; towards it this step: as against cells ([[#MYWH16]]), a body faster
                         ;; than its margin a step reaches that far, to meet an edge or a corner
                         ;; before it strikes
                         (wx (- (aref bvx i) (aref vx b))) (wy (- (aref bvy i) (aref vy b)))
                         (wz (- (aref bvz i) (aref vz b)))
                         (travel (step-travel wx wy wz dt gstep))
                         (reach (body-reach r travel margin limit))
                         (key (box-key (handle-index (aref handle i)) (aref id b))))
                    (with-cell-closest-point (nx ny nz px py pz sep d2 ox oy oz)
                        (cx cy cz r bx0 by0 bz0 bx1 by1 bz1)
                      (when (<= d2 (* reach reach))
                        ;; the normal at the point it will strike, as a cell's
                        (multiple-value-bind (nx ny nz sep)
                            (multiple-value-bind (nx ny nz sep) (finish)
                              (impact-normal nx ny nz sep cx cy cz r wx wy wz dt threshold bx0 by0 bz0 bx1 by1 bz1))
                          (setf touched t)
                          (touch-contact contacts table key +contact-box+ (aref handle i) +no-body+
                                         nx ny nz sep px py pz (aref vx b) (aref vy b) (aref vz b))))
                      (multiple-value-bind (nx ny nz px py pz sep)
                          (inside-face nil cx cy cz r bx0 by0 bz0 bx1 by1 bz1 0 0 0)
                        (setf touched t)
                        (touch-contact contacts table key +contact-box+ (aref handle i) +no-body+
                                       nx ny nz sep px py pz (aref vx b) (aref vy b) (aref vz b))))))))))))
          ;; the step's squeeze rules look for box rows only when some body touched a box ([[#SQU33Z]])
      (when touched (setf (physics-world-box-touch-step world) (physics-world-step-count world)))
      world)))
;; Boxes touch as moving terrain:1 ends here

;; [[file:../physics.org::#PRUN3D][Contacts not found this step are pruned:1]]
(defun prune-phase (world)
  "The prune phase: drop every contact not seen this step (a touching one ends with an :end event). When
the table's cursor has missed as often as there are rows, put the rows found this step in the
order they were found; otherwise swap-remove, patching the table entry of the row that fills
the hole. #PRUN3D"
  (declare #.+kernel-policy+)
  (let* ((contacts (physics-world-contacts world))
         (table (physics-world-contact-table world))
         (step (physics-world-step-count world))
         (reorder (>= (contact-table-misses table) (max 64 (contact-columns-length contacts)))))
    (declare (type contact-columns contacts) (type contact-table table) (type fixnum step))
    ;; the room a reordering needs grows with the contact buffer, so reordering never allocates
    (contact-columns-ensure-capacity (physics-world-contact-scratch world) (contact-columns-capacity contacts))
    (let* ((m (contact-columns-length contacts))
           (drops (setf (physics-world-contact-drops world)
                        (fixnum-room (physics-world-contact-drops world) m :keep 0)))
           ;; a place for each worker a world may have (+physics-max-workers+, [[#W0RKP1]])
           (ends (make-array 64 :element-type 'fixnum))
           (shares (list-unseen-rows world m step drops ends)))
      (declare (type index m) (type fixnum-column drops) (type fixnum shares) (dynamic-extent ends))
      ;; the rows not seen, from the last down: the last share's list first, each from its end
      (loop for w of-type fixnum from (1- shares) downto 0
            do (loop for i of-type fixnum from (1- (aref ends w)) downto (piece-bounds 0 m w shares)
                     do (let ((row (aref drops i)))
                          (with-contact-columns (order touching key handle-a handle-b geometry) contacts
                            (when (= (aref touching row) 1)
                              (push-event world +event-end+ (aref handle-a row) (aref handle-b row)
                                          (contact@ geometry row px) (contact@ geometry row py) (contact@ geometry row pz) 0.0))
                            (contact-table-delete table (aref key row))
                            (if reorder
                                (setf (aref order row) -1)
                                (let ((moved (contact-columns-swap-remove contacts row)))
                                  (when (>= moved 0)
                                    (contact-table-put table (aref key row) row)))))))))
    (when reorder
      (let ((order (contact-columns-order contacts))
            (slots (contact-table-slots table)))
        ;; every key left in the table names a row found this step; point it at that row's place
        (loop for i of-type fixnum from 0 below (length slots) by 2
              unless (= (aref slots i) -1)
                do (setf (aref slots (1+ i)) (aref order (aref slots (1+ i)))))
        ;; the rows' moves in pieces, one a worker ([[#SPL1T5]]): each row goes to its own place
        (flet ((runner (move rows) (run-row-pieces world rows :reorder move)))
          (declare (dynamic-extent #'runner))
          (contact-columns-permute contacts (physics-world-contact-scratch world) order
                                   (contact-table-touched table) #'runner))
        (setf (contact-table-misses table) 0)))
    world))

(defun list-unseen-rows (world m step drops ends)
  "List, in DROPS, WORLD's contact rows among the first M not seen at STEP: in pieces, one a
worker ([[#SPL1T5]]), each share of the rows listing its own in order from its first row's place
on and writing where its list ends into ENDS at its worker. Return how many shares ran. #PRUN3D"
  (declare (type index m) (type fixnum step) (type fixnum-column drops ends) #.+kernel-policy+)
  (let ((seen (contact-columns-seen (physics-world-contacts world))))
    (declare (type fixnum-column seen))
    (flet ((unseen (worker count)
             (declare (type fixnum worker count))
             (multiple-value-bind (from to) (piece-bounds 0 m worker count)
               (declare (type index from to))
               (let ((at from))
                 (declare (type index at))
                 (loop for row of-type index from from below to
                       unless (= (aref seen row) step)
                         do (setf (aref drops at) row)
                            (incf at))
                 (setf (aref ends worker) at)))))
      (declare (dynamic-extent #'unseen))
      (run-pieces world m :unseen #'unseen))))
;; Contacts not found this step are pruned:1 ends here

;; [[file:../physics.org::#SSMPYW][Colours are the lanes:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +constraint-columns+
    '(nx ny nz t1x t1y t1z t2x t2y t2z ra rb ima imb iia iib separation
      normal-mass tangent-mass rolling-mass friction bias-rate mass-scale
      impulse-scale normal-impulse tangent-impulse-1 tangent-impulse-2 gap
      ;; the columns only some worlds have ([[#FEAT5X]]): the box's velocity along the normal
      ;; and the frame (written as its x, y, z until the frame pass: +constraint-column-aliases+),
      ;; the largest push the events and restitution read, the approach speed the events
      ;; report, rolling resistance's, and restitution's
      kvn kvt1 kvt2 max-normal-impulse
      relative-velocity rolling-limit rolling-impulse-x rolling-impulse-y rolling-impulse-z
      restitution)
    "The float columns of a constraint's main block, in the order they sit in it: those every
world needs, then those a world's features may leave out, last. #SSMPYW")
  (defparameter +constraint-side-columns+
    '(spin-limit spin-impulse armed-speed)
    "The float columns of a constraint's side block, read only by the rows that need them:
friction's two, then restitution's. #SSMPYW")
  (defparameter +constraint-column-aliases+
    '((kvx . kvn) (kvy . kvt1) (kvz . kvt2))
    "Each name of a column that holds one thing before the frame pass and another after it, with
the column's own name: the fill writes the box's velocity along the world's axes as kvx, kvy and
kvz, and the frame pass turns it, in the same three columns, into its parts along the normal and
the two tangents, kvn, kvt1 and kvt2. #SSMPYW")
  (defun constraint-side-column-p (column)
    "True when COLUMN sits in the side block. #SSMPYW"
    (member column +constraint-side-columns+ :test #'string= :key #'symbol-name))
  (defun constraint-offset (column)
    "Where COLUMN's eight lanes begin inside a block of constraints, the main block's or, for a
column of +constraint-side-columns+, the side block's; a name of +constraint-column-aliases+ is
its column's. #SSMPYW"
    (setf column (or (cdr (assoc column +constraint-column-aliases+ :test #'string= :key #'symbol-name))
                     column))
    (* 8 (or (position column +constraint-columns+ :test #'string= :key #'symbol-name)
             (position column +constraint-side-columns+ :test #'string= :key #'symbol-name)
             (error "no constraint column ~A" column)))))

(defconstant +constraint-block+ (* 8 (length +constraint-columns+))
  "Floats in a main block of eight constraints: eight lanes of each float column. #SSMPYW")

(defconstant +constraint-side-block+ (* 8 (length +constraint-side-columns+))
  "Floats in a side block of eight constraints: eight lanes of each side column. #SSMPYW")

(defconstant +constraint-origin+ 4
  "Floats before the first block of the constraint buffer, so that on an array whose data
begin 16 bytes past a 64-byte boundary every column's eight lanes start on a 32-byte
boundary. #SSMPYW")

(deftype constraint-block-size ()
  "The floats of one block of constraints, main or side: at most a main block of every column.
Bounded so, the base of a constraint (constraint-base) is a fixnum the compiler can see, and
every column read in a kernel is fixnum arithmetic, not a call to generic addition. #SSMPYW"
  `(integer 0 ,+constraint-block+))

(defstruct (constraint-columns (:constructor make-constraint-columns
                                  (&optional (block +constraint-block+) (side-block +constraint-side-block+))))
  "The contacts of one step as solver rows, written in colour order: three fixnum columns, and
the float columns in blocks of eight rows, each column's eight lanes contiguous; BLOCK floats a
main block, the first BLOCK/8 columns of +constraint-columns+, and SIDE-BLOCK a side block, the
first SIDE-BLOCK/8 of +constraint-side-columns+. #SSMPYW"
  (block +constraint-block+ :type constraint-block-size)
  (side-block +constraint-side-block+ :type constraint-block-size)
  (length 0 :type index)
  (capacity 0 :type index)
  (data (make-array 0 :element-type 'single-float) :type f32-column)
  (side (make-array 0 :element-type 'single-float) :type f32-column)
  (contact (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (body-a (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (body-b (make-array 0 :element-type 'fixnum) :type fixnum-column))
;; Colours are the lanes:1 ends here

;; [[file:../physics.org::#SSMPYW][Colours are the lanes:2]]
(defun constraint-columns-ensure-capacity (buffer rows)
  "Grow BUFFER to hold ROWS constraints, in whole blocks; return it. #SSMPYW"
  (when (> rows (constraint-columns-capacity buffer))
    (let ((new (* 8 (ceiling (max rows (* 2 (constraint-columns-capacity buffer)) 64) 8))))
      (flet ((grow (old type n)
               (let ((fresh (make-array n :element-type type :initial-element (coerce 0 type))))
                 (replace fresh old) fresh)))
        (setf (constraint-columns-data buffer)
              (grow (constraint-columns-data buffer) 'single-float
                    (+ +constraint-origin+ (* (floor new 8) (constraint-columns-block buffer))))
              (constraint-columns-side buffer)
              (grow (constraint-columns-side buffer) 'single-float
                    (+ +constraint-origin+ (* (floor new 8) (constraint-columns-side-block buffer))))
              (constraint-columns-contact buffer) (grow (constraint-columns-contact buffer) 'fixnum new)
              (constraint-columns-body-a buffer) (grow (constraint-columns-body-a buffer) 'fixnum new)
              (constraint-columns-body-b buffer) (grow (constraint-columns-body-b buffer) 'fixnum new)
              (constraint-columns-capacity buffer) new))))
  buffer)

(declaim (inline constraint-base))
(defun constraint-base (k &optional (block +constraint-block+))
  "The index of constraint K's lane of the first column of its block, in blocks of BLOCK floats. #SSMPYW"
  (declare (type index k) (type constraint-block-size block))
  (+ +constraint-origin+ (* (ash k -3) block) (logand k 7)))

(defmacro with-constraint-block ((&rest fixnum-columns) buffer &body body)
  "Run BODY with DATA bound to BUFFER's main blocks, STRIDE to the floats of one, each of
FIXNUM-COLUMNS (contact, body-a, body-b) bound to its column, (constraint-base K) naming the
base of constraint K in BUFFER's main blocks, (side-floats) BUFFER's side blocks and (side-base
K) the base of constraint K in them, and (@ COLUMN) naming COLUMN of the constraint whose base
is the variable BASE, or for a side column, of constraint K. The side blocks are reached through
BUFFER where they are read, not bound for the whole body: a kernel's loop keeps one more value
alive, not two. #SSMPYW"
  (let ((b (gensym "BUFFER")))
    `(let* ((,b ,buffer)
            (data (constraint-columns-data ,b))
            (stride (constraint-columns-block ,b))
            ,@(loop for c in fixnum-columns
                    collect `(,c (,(intern (format nil "CONSTRAINT-COLUMNS-~A" c)) ,b))))
       (declare (type f32-column data) (type fixnum-column ,@fixnum-columns)
                (type constraint-block-size stride)
                (ignorable ,b data stride ,@fixnum-columns))
       (macrolet ((@ (column) (if (constraint-side-column-p column)
                                  `(block-ref (side-floats) (side-base k) ,(constraint-offset column))
                                  `(block-ref data base ,(constraint-offset column))))
                  (constraint-base (k) `(+ +constraint-origin+ (* (ash ,k -3) stride) (logand ,k 7)))
                  (side-floats () '(constraint-columns-side ,b))
                  ;; the side block's length is a constraint-block-size, as the main's: the
                  ;; base needs no overflow test and no generic arithmetic
                  (side-base (k) `(+ +constraint-origin+
                                     (* (ash (the index ,k) -3) (constraint-columns-side-block ,',b))
                                     (logand ,k 7))))
         ,@body))))

(defun constraint-place (buffer k column)
  "The float column of BUFFER that holds COLUMN of constraint K, and the index in it: for the
claims and the tools, which name a column rather than know its block. #SSMPYW"
  (if (constraint-side-column-p column)
      (values (constraint-columns-side buffer)
              (+ (constraint-base k (constraint-columns-side-block buffer)) (constraint-offset column)))
      (values (constraint-columns-data buffer)
              (+ (constraint-base k (constraint-columns-block buffer)) (constraint-offset column)))))

(defun constraint-ref (buffer k column)
  "COLUMN of constraint K in BUFFER. #SSMPYW"
  (multiple-value-bind (floats i) (constraint-place buffer k column) (aref floats i)))

(defun (setf constraint-ref) (value buffer k column)
  "Set COLUMN of constraint K in BUFFER to VALUE. #SSMPYW"
  (multiple-value-bind (floats i) (constraint-place buffer k column) (setf (aref floats i) value)))

(defun ensure-solver-scratch (world n contacts)
  "Size WORLD's per-step scratch for N awake bodies (plus the dummy) and CONTACTS contacts. #SSMPYW"
  ;; the colour masks have one entry per solver row
  (when (< (length (physics-world-color-masks world)) (1+ n))
    (let ((rows (max (1+ n) (* 2 (length (physics-world-color-masks world))) 64)))
      (setf (physics-world-velocities world)
            (make-array (solver-row rows) :element-type 'single-float :initial-element 0.0)
            (physics-world-deltas world)
            (make-array (delta-row rows) :element-type 'single-float :initial-element 0.0)
            (physics-world-color-masks world)
            (make-array rows :element-type 'fixnum :initial-element 0)
            (physics-world-braced world)
            (make-array rows :element-type 'fixnum :initial-element 0)
            (physics-world-held world)
            (make-array rows :element-type 'fixnum :initial-element 0))))
  (setf (physics-world-contact-colors world) (fixnum-room (physics-world-contact-colors world) contacts :keep 0)
        (physics-world-contact-rows world) (fixnum-room (physics-world-contact-rows world) (* 2 contacts) :keep 0)
        (physics-world-contact-crosses world) (fixnum-room (physics-world-contact-crosses world) contacts :keep 0))
  (constraint-columns-ensure-capacity (physics-world-constraints world) contacts)
  world)
;; Colours are the lanes:2 ends here

;; [[file:../physics.org::#SSMPYW][Colours are the lanes:3]]
(declaim (inline lowest-bit highest-bit))
(defun lowest-bit (x)
  "The index of the lowest set bit of X > 0. #SSMPYW"
  (declare (type (unsigned-byte 32) x))
  (1- (integer-length (logand x (- x)))))

(defun highest-bit (x)
  "The index of the highest set bit of X > 0. #SSMPYW"
  (declare (type (unsigned-byte 32) x))
  (1- (integer-length x)))

(defconstant +colour-pieces+ 4
  "The most pieces the colouring cuts the awake rows into. #SSMPYW")

(defconstant +colour-piece-rows+ 1024
  "The fewest awake rows a colouring piece holds. #SSMPYW")

(defun colour-pieces (n)
  "How many pieces the colouring cuts N awake rows into: one per +colour-piece-rows+ rows, at
least one and at most +colour-pieces+. #SSMPYW"
  (declare (type index n))
  (max 1 (min +colour-pieces+ (floor n +colour-piece-rows+))))

(defun colour-piece-scale (n pieces)
  "The factor that takes an awake row of N to its piece of PIECES (colour-piece). #SSMPYW"
  (declare (type index n pieces))
  (if (zerop n) 0 (ceiling (ash pieces 40) n)))

(declaim (inline colour-piece))
(defun colour-piece (l scale last)
  "The colouring piece of the awake row L: L times SCALE over 2^40, at most LAST (0 when LAST
is). Without a division, and fixed by the rows and the pieces alone. #SSMPYW"
  (declare (type index l last) (type (unsigned-byte 62) scale))
  (if (zerop last) 0 (min last (ash (ldb (byte 62 0) (* l scale)) -40))))

(declaim (inline colour-two-body))
(defun colour-two-body (masks colors c la lb)
  "Give contact C, between the awake rows LA and LB, the lowest of colours 0-19 free at both in
MASKS, or the overflow colour; mark it in both masks; return it. #SSMPYW"
  (declare (type fixnum-column masks colors) (type index c la lb))
  (let ((free (logand (lognot (logior (aref masks la) (aref masks lb)))
                      (1- (ash 1 +physics-dynamic-colors+))))
        (color +physics-max-colors+))
    (declare (type fixnum color))
    (unless (zerop free)
      (setf color (lowest-bit free))
      (setf (aref masks la) (logior (aref masks la) (ash 1 color))
            (aref masks lb) (logior (aref masks lb) (ash 1 color))))
    (setf (aref colors c) color)))

(declaim (inline colour-one-sided))
(defun colour-one-sided (masks colors c l used)
  "Give contact C, one-sided at the awake row L, the highest colour of USED free at L in MASKS,
else the lowest free colour, else the overflow colour; mark it; return it. #SSMPYW"
  (declare (type fixnum-column masks colors) (type index c l) (type (unsigned-byte 32) used))
  (let ((free (logand (lognot (aref masks l)) (1- (ash 1 +physics-max-colors+))))
        (color +physics-max-colors+))
    (declare (type fixnum color))
    (cond ((plusp (logand free used)) (setf color (highest-bit (logand free used))))
          ((plusp free) (setf color (lowest-bit free))))
    (when (< color +physics-max-colors+)
      (setf (aref masks l) (logior (aref masks l) (ash 1 color))))
    (setf (aref colors c) color)))

(defmacro with-colour-pieces ((p0 p1) (pieces worker count) &body body)
  "Run BODY with P0 and P1 bound to the first colouring piece of WORKER's share, of COUNT, of
PIECES pieces, and the one after its last. #SSMPYW"
  `(let ((,p0 (floor (* ,pieces ,worker) ,count)) (,p1 (floor (* ,pieces (1+ ,worker)) ,count)))
     (declare (type index ,p0 ,p1))
     ,@body))
;; Colours are the lanes:3 ends here

;; [[file:../physics.org::#SSMPYW][Colours are the lanes:4]]
(defun color-contacts (world &optional (two-body t))
  "Greedy colouring in two passes, each in pieces of the awake rows. First every two-body
contact takes the lowest of colours 0-19 free at both its bodies: the contacts within a piece by
the piece, in contact order, then those across two pieces, in contact order (a world without body
contacts, TWO-BODY false, has none: every contact is one-sided). Then every one-sided contact
takes, at its awake body, the highest free colour among those the two-body contacts used, or
failing that the lowest free colour above them, by its body's piece. Anything else goes to the
overflow colour 24. Fills the colour of each contact, its two sides' awake rows (-1 for a side
that is not an awake body) at 2c and 2c+1 of the world's contact rows, for the prepare phase to
read instead of looking each handle up again, and the colour starts, each colour but the
overflow starting on a multiple of eight; returns the number of colours used. #SSMPYW"
  (let* ((m (contact-columns-length (physics-world-contacts world)))
         (n (body-columns-length (physics-world-awake world)))
         (pieces (colour-pieces n))
         (scale (colour-piece-scale n pieces))
         (last (1- pieces))
         (crosses (physics-world-contact-crosses world))
         (counts (physics-world-colour-counts world))
         ;; a place for each worker a world may have (+physics-max-workers+, [[#W0RKP1]])
         (ends (make-array 64 :element-type 'fixnum))
         (looked 1))
    (declare (type fixnum-column crosses counts) (type index m n pieces last)
             (type (unsigned-byte 62) scale) (type fixnum looked)
             (dynamic-extent ends) #.+kernel-policy+)
    (setf looked (look-up-contact-rows world m n scale last two-body crosses ends))
    (if (= pieces 1)
        (color-one-piece world m two-body counts)
        (color-pieces world m scale last two-body crosses ends looked counts)))
  ;; the colours' counts, piece by piece, then prefix sums, each colour but the overflow
  ;; padded to a whole block of eight rows
  (let* ((n (body-columns-length (physics-world-awake world)))
         (starts (physics-world-color-starts world))
         (counts (physics-world-colour-counts world)))
    (declare (type fixnum-column starts counts) (type index n))
    (fill starts 0)
    (dotimes (p (colour-pieces n))
      (dotimes (c (1+ +physics-max-colors+))
        (incf (aref starts (1+ c)) (aref counts (+ (* p (1+ +physics-max-colors+)) c)))))
    (loop with at of-type index = 0
          for c from 0 to +physics-max-colors+
          for count of-type index = (aref starts (1+ c))
          do (setf (aref starts c) at)
             (incf at (if (< c +physics-max-colors+) (* 8 (ceiling count 8)) count))
          count (plusp count) into used
          finally (setf (aref starts (1+ +physics-max-colors+)) at)
                  (return used))))
;; Colours are the lanes:4 ends here

;; [[file:../physics.org::#SSMPYW][Colours are the lanes:5]]
(defun color-one-piece (world m two-body counts)
  "The colouring's two passes over WORLD's M contacts as one piece, on one thread: pass one
over the two-body contacts (when TWO-BODY) in contact order, then pass two; count the colours
into the first 25 places of COUNTS. #SSMPYW"
  (declare (type index m) (type fixnum-column counts) #.+kernel-policy+)
  (let ((masks (physics-world-color-masks world))
        (colors (physics-world-contact-colors world))
        (rows (physics-world-contact-rows world))
        (top -1))
    (declare (type fixnum-column masks colors rows) (type fixnum top))
    (when two-body
      (dotimes (c m)
        (let ((la (aref rows (* 2 c))) (lb (aref rows (1+ (* 2 c)))))
          (declare (type fixnum la lb))
          (when (and (>= la 0) (>= lb 0))
            (let ((color (colour-two-body masks colors c la lb)))
              (when (< top color +physics-max-colors+) (setf top color)))))))
    (fill counts 0 :end (1+ +physics-max-colors+))
    (let ((used (1- (ash 1 (1+ top)))))
      (declare (type (unsigned-byte 32) used))
      (dotimes (c m)
        (let ((color (aref colors c)))
          (declare (type fixnum color))
          (when (= color -1)
            (setf color (colour-one-sided masks colors c (max (aref rows (* 2 c)) (aref rows (1+ (* 2 c))))
                                          used)))
          (incf (aref counts color)))))))

(defun color-pieces (world m scale last two-body crosses ends looked counts)
  "The colouring's two passes over WORLD's M contacts in pieces (colour-piece of SCALE, the last
LAST): pass one within each piece when TWO-BODY, then the contacts across pieces that the
LOOKED shares of the look-up listed in CROSSES up to their ENDS, then pass two by piece
(color-one-sided-contacts), counting into COUNTS. #SSMPYW"
  (declare (type index m last) (type (unsigned-byte 62) scale) (type fixnum looked)
           (type fixnum-column crosses ends counts) #.+kernel-policy+)
  (let ((pieces (1+ last))
        (masks (physics-world-color-masks world))
        (colors (physics-world-contact-colors world))
        (rows (physics-world-contact-rows world))
        (tops (make-array (1+ +colour-pieces+) :element-type 'fixnum :initial-element -1)))
    (declare (type index pieces) (type fixnum-column masks colors rows) (dynamic-extent tops))
    (when two-body
      ;; pass one, within each piece: its contacts touch its bodies alone
      (flet ((two-body-piece (worker count)
               (declare (type fixnum worker count))
               (with-colour-pieces (p0 p1) (pieces worker count)
                 ;; a worker without a piece walks no contact
                 (dotimes (c (if (< p0 p1) m 0))
                   (let ((la (aref rows (* 2 c))) (lb (aref rows (1+ (* 2 c)))))
                     (declare (type fixnum la lb))
                     (when (and (>= la 0) (>= lb 0))
                       (let ((p (colour-piece la scale last)))
                         (when (and (= p (colour-piece lb scale last)) (<= p0 p) (< p p1))
                           (let ((color (colour-two-body masks colors c la lb)))
                             (when (< (aref tops p) color +physics-max-colors+)
                               (setf (aref tops p) color)))))))))))
        (declare (dynamic-extent #'two-body-piece))
        (run-pieces world m :colour-pairs #'two-body-piece))
      ;; then the contacts across two pieces, in contact order: each share of the look-up
      ;; listed its own from the share's first place on
      (dotimes (w looked)
        (loop for i of-type index from (piece-bounds 0 m w looked) below (aref ends w)
              do (let* ((c (aref crosses i))
                        (color (colour-two-body masks colors c (aref rows (* 2 c)) (aref rows (1+ (* 2 c))))))
                   (declare (type index c))
                   (when (< (aref tops +colour-pieces+) color +physics-max-colors+)
                     (setf (aref tops +colour-pieces+) color))))))
    (color-one-sided-contacts world m scale last
                              (1- (ash 1 (1+ (loop for top across tops maximize top)))) counts)))
;; Colours are the lanes:5 ends here

;; [[file:../physics.org::#SSMPYW][Colours are the lanes:6]]
(defun look-up-contact-rows (world m n scale last two-body crosses ends)
  "The colouring's first job, in pieces: every one of WORLD's M contacts' awake rows into the
contact rows and its colour unset (-1), the N awake rows' masks cleared; when TWO-BODY, each
share lists the contacts whose two bodies lie in different pieces (colour-piece of SCALE and
LAST) into
CROSSES from its first contact's place on, and writes where its list ends into ENDS at its worker.
Return how many shares ran. #SSMPYW"
  (declare (type index m n last) (type (unsigned-byte 62) scale) (type fixnum-column crosses ends)
           #.+kernel-policy+)
  (let* ((ids (physics-world-ids world))
         (masks (physics-world-color-masks world))
         (colors (physics-world-contact-colors world))
         (rows (physics-world-contact-rows world))
         (sets (handle-table-set ids))
         (locals (handle-table-local ids)))
    (declare (type fixnum-column masks colors rows sets locals))
    (with-contact-columns (handle-a handle-b) (physics-world-contacts world)
      (flet ((awake-row (h)
               (declare (type fixnum h))
               (if (and (>= h 0) (= (aref sets (handle-index h)) +set-awake+))
                   (aref locals (handle-index h))
                   -1)))
        (declare (inline awake-row))
        ;; each contact's rows and each body's mask are its own ([[#SPL1T5]])
        (flet ((look-up (worker count)
                 (declare (type fixnum worker count))
                 (multiple-value-bind (from to) (piece-bounds 0 m worker count)
                   (declare (type index from to))
                   (let ((at from))
                     (declare (type index at))
                     (loop for c of-type index from from below to
                           do (let ((la (awake-row (aref handle-a c))) (lb (awake-row (aref handle-b c))))
                                (declare (type fixnum la lb))
                                (setf (aref rows (* 2 c)) la (aref rows (1+ (* 2 c))) lb
                                      (aref colors c) -1)
                                (when (and two-body (plusp last) (>= la 0) (>= lb 0)
                                           (/= (colour-piece la scale last) (colour-piece lb scale last)))
                                  (setf (aref crosses at) c)
                                  (incf at))))
                     (setf (aref ends worker) at)))
                 (multiple-value-bind (from to) (piece-bounds 0 (1+ n) worker count)
                   (declare (type index from to))
                   (fill masks 0 :start from :end to)
                   ;; the solver's body state, row by row ([[#PRLD5V]])
                   (load-solver-bodies (physics-world-awake world) (physics-world-velocities world)
                                       (physics-world-deltas world) n from to))))
          (declare (dynamic-extent #'look-up))
          (run-pieces world m :colour-rows #'look-up))))))

(defun color-one-sided-contacts (world m scale last used counts)
  "The colouring's second pass, in pieces: every one of WORLD's M contacts still without a colour
takes one at its awake body (colour-one-sided, the colours USED by the first pass), by its body's
piece (colour-piece of SCALE, the last LAST); and each piece counts into COUNTS, 25 a piece, the
colours of the contacts whose last awake row is its own. #SSMPYW"
  (declare (type index m last) (type (unsigned-byte 62) scale) (type (unsigned-byte 32) used)
           (type fixnum-column counts) #.+kernel-policy+)
  (let ((masks (physics-world-color-masks world))
        (colors (physics-world-contact-colors world))
        (rows (physics-world-contact-rows world)))
    (declare (type fixnum-column masks colors rows))
    (flet ((one-sided-piece (worker count)
             (declare (type fixnum worker count))
             (with-colour-pieces (p0 p1) ((1+ last) worker count)
               (fill counts 0 :start (* p0 (1+ +physics-max-colors+)) :end (* p1 (1+ +physics-max-colors+)))
               (when (< p0 p1)
                 (dotimes (c m)
                   (let* ((color (aref colors c))
                          ;; one piece needs the rows only of a contact it colours
                          (l (if (and (zerop last) (/= color -1))
                                 0
                                 (max (aref rows (* 2 c)) (aref rows (1+ (* 2 c))))))
                          (p (colour-piece l scale last)))
                     (declare (type fixnum color) (type index l p))
                     (when (and (<= p0 p) (< p p1))
                       (when (= color -1) (setf color (colour-one-sided masks colors c l used)))
                       (incf (aref counts (+ (* p (1+ +physics-max-colors+)) color))))))))))
      (declare (dynamic-extent #'one-sided-piece))
      (run-pieces world m :colour-sides #'one-sided-piece))))

(defun physics-world-overflow-count (world)
  "How many of the last step's contacts fell into the overflow colour. #SSMPYW"
  (check-world world 'physics-world-overflow-count)
  (let ((starts (physics-world-color-starts world)))
    (- (aref starts (1+ +physics-max-colors+)) (aref starts +physics-max-colors+))))
;; Colours are the lanes:6 ends here

;; [[file:../physics.org::#KTXT7V][One kernel text for every feature set:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun split-definition-body (body)
    "BODY of a definition as three values: its forms, its declarations and its docstring. #KTXT7V"
    (let ((documentation (and (stringp (first body)) (rest body) (pop body))))
      (loop while (and (consp (first body)) (eq (car (first body)) 'declare))
            collect (pop body) into declarations
            finally (return (values body declarations documentation)))))

  (defun featured-kernel-form (name features)
    "A form whose value is the kernel NAME (a define-featured-kernel) compiled for FEATURES: its
text, with each if-feature resolved for FEATURES. #KTXT7V"
    (destructuring-bind (operators lambda-list declarations forms tested) (get name 'featured-kernel)
      (declare (ignore tested))
      (let ((function `(lambda ,lambda-list ,@declarations (with-features ,features ,@forms))))
        (if operators `(macrolet ,operators ,function) function))))

  (defun kernel-feature-key (name features)
    "The features among FEATURES that the kernel NAME tests, in the order of +physics-features+. #KTXT7V"
    (let ((tested (fifth (get name 'featured-kernel))))
      (remove-if-not (lambda (f) (and (member f tested) (member f features))) +physics-features+))))

(defstruct (kernel-variant (:constructor make-kernel-variant (kernels warm-start solve prepare-frames
                                                                wide-warm-start wide-solve wide-prepare-frames)))
  "The solver kernels a world of some features runs in the family KERNELS: each a function, or
the name of the general kernel ([[#FEAT5X]]). #KTXT7V"
  kernels warm-start solve prepare-frames wide-warm-start wide-solve wide-prepare-frames)

(defmacro with-features ((&rest features) &body body)
  "Run BODY with (if-feature FEATURE THEN &optional ELSE) standing for THEN when FEATURE is one
of FEATURES and for ELSE otherwise, chosen at macro-expansion; FEATURE may be (:or F ...), for
any of the Fs. #KTXT7V"
  `(macrolet ((if-feature (feature then &optional else)
                (if (if (and (consp feature) (eq (first feature) :or))
                        (intersection (rest feature) ',features)
                        (member feature ',features))
                    then else)))
     ,@body))

(defmacro define-featured-kernel ((name &key features operators) lambda-list &body body)
  "Define NAME, a function of LAMBDA-LIST, compiled with every feature; keep its text, which
tests the FEATURES listed with if-feature, so that featured-kernel-form can compile it for
fewer; OPERATORS, macrolet definitions, wrap the text wherever it is compiled. #KTXT7V"
  (multiple-value-bind (forms declarations documentation) (split-definition-body body)
    (let ((function `(defun ,name ,lambda-list ,@(when documentation (list documentation)) ,@declarations
                       (with-features ,+physics-features+ ,@forms))))
      `(progn
         (eval-when (:compile-toplevel :load-toplevel :execute)
           (setf (get ',name 'featured-kernel) '(,operators ,lambda-list ,declarations ,forms ,features)))
         ,(if operators `(macrolet ,operators ,function) function)))))
;; One kernel text for every feature set:1 ends here

;; [[file:../physics.org::#PR3PAR][Preparing the constraints:1]]
(defconstant +brace-braced+ 1
  "Bracing mark: the body is braced, static to a much heavier body resting on it. #PR3PAR")

(defconstant +brace-link+ 2
  "Bracing mark: in the contacts' pass, the body under this one was braced at the step before;
once settled, this body is a link of a column (always with +brace-braced+). #PR3PAR")

(defconstant +brace-unsettled+ 4
  "Bracing mark: the body's contact with the body straight under it is deeper than 1.05 slops,
so it does not count as still for sleep. #PR3PAR")

(defconstant +brace-on-column+ 8
  "Bracing mark: the body rests within 8 degrees of the vertical on a body at least as light. #PR3PAR")

(defconstant +brace-support+ 16
  "Bracing mark: one support; a body's mark counts its supports in these units, above the four
flags. #PR3PAR")

(declaim (inline spin-arm))
(defun spin-arm (radius slop)
  "The lever of spin friction for a ball of RADIUS resting SLOP deep on something flat: two
thirds of the radius of its contact patch, sqrt(2 RADIUS SLOP). #PR3PAR"
  (declare (type single-float radius slop))
  (* (/ 2.0 3.0) (fsqrt (* 2.0 radius slop))))

(declaim (inline rests-static-p))
(defun rests-static-p (braced inverse-mass brace-ratio lower upper rise)
  "Whether the awake row UPPER rests on the BRACED row LOWER as on something static: more than
BRACE-RATIO times heavier and RISE (the upward part of the normal from LOWER to UPPER) above 0.9,
or a link of a column (UPPER's mark in BRACED holds +brace-link+), at least as heavy and RISE above
0.99. #PR3PAR"
  (declare (type fixnum-column braced) (type f32-column inverse-mass) (type index lower upper)
           (type single-float brace-ratio rise))
  (and (logtest (aref braced lower) +brace-braced+)
       (or (and (> rise 0.9) (> (aref inverse-mass lower) (* brace-ratio (aref inverse-mass upper))))
           (and (> rise 0.99) (logtest (aref braced upper) +brace-link+)
                (>= (aref inverse-mass lower) (aref inverse-mass upper))))))

(declaim (inline brace-side))
(defun brace-side (braced inverse-mass brace-ratio la lb rise)
  "Which side of a contact between awake rows LA and LB is static to the other: :a when LB rests
on LA as on something static (rests-static-p, RISE the upward part of the normal from LA to LB);
:b the other way round; else nil. #PR3PAR"
  (declare (type fixnum-column braced) (type f32-column inverse-mass) (type index la lb)
           (type single-float brace-ratio rise))
  (cond ((rests-static-p braced inverse-mass brace-ratio la lb rise) :a)
        ((rests-static-p braced inverse-mass brace-ratio lb la (- rise)) :b)))

(defun held-mass-bound (world)
  "The most mass a contact of WORLD with something static can hold up this step: the awake bodies'
mass, for a sleeper is static and holds itself up; while kinematic boxes are posted, which press
with no mass of their own, 1e30 kg, beyond any world's. #PR3PAR"
  (let ((awake (physics-world-awake world)) (mass 0.0))
    (declare (type single-float mass))
    (if (plusp (box-columns-length (physics-world-boxes world)))
        1e30
        (with-body-columns (inverse-mass) awake
          (dotimes (i (body-columns-length awake) mass)
            (incf mass (/ 1.0 (aref inverse-mass i))))))))

(defvar *prepare-short-path* t
  "When false, the prepare fill sends every row through its general path; the claim that the
short path changes no bit compares the two. #PR3PAR")
;; Preparing the constraints:1 ends here

;; [[file:../physics.org::#PRLD5V][Loading the solver's bodies:1]]
(declaim (inline size-constraint-buffer))
(defun size-constraint-buffer (world cbuf)
  "Give CBUF, WORLD's constraint buffer, room and length for the rows of every colour, padding
included, as the colouring laid them out. #PRLD5V"
  (declare (type constraint-columns cbuf))
  (let ((rows (aref (physics-world-color-starts world) (1+ +physics-max-colors+))))
    (constraint-columns-ensure-capacity cbuf rows)
    (setf (constraint-columns-length cbuf) rows)))

(defun load-solver-bodies (awake v d n from to)
  "Load the solver's body state for the rows FROM below TO of AWAKE's N and the dummy row N after
them: each awake row's velocities into its solver row of V, zero velocities in the dummy row,
and zero deltas in D. Each row is its own, so the colouring's look-up loads the rows in its
pieces ([[#SSMPYW]]). #PRLD5V"
  (declare (type body-columns awake) (type f32-column v d) (type index n from to))
  (with-body-columns (vx vy vz wx wy wz) awake
    (loop for i of-type index from from below (min to n)
          do (let ((o (solver-row i)))
               (setf (aref v o) (aref vx i) (aref v (+ o 1)) (aref vy i) (aref v (+ o 2)) (aref vz i)
                     (aref v (+ o 3)) (aref wx i) (aref v (+ o 4)) (aref wy i) (aref v (+ o 5)) (aref wz i)))))
  (when (< n to) (fill v 0.0 :start (solver-row n) :end (solver-row (1+ n))))
  (when (< from to) (fill d 0.0 :start (if (zerop from) 0 (delta-row from)) :end (delta-row to))))
;; Loading the solver's bodies:1 ends here

;; [[file:../physics.org::#PRBR4C][Marking the braced bodies:1]]
(declaim (inline masses-span-brace-ratio-p))
(defun masses-span-brace-ratio-p (inverse-mass n brace-ratio)
  "Whether one of the N awake rows (N above zero) of INVERSE-MASS is more than BRACE-RATIO times
heavier than another: without that, or a column's link, no body is static to another. #PRBR4C"
  (declare (type f32-column inverse-mass) (type index n) (type single-float brace-ratio))
  (let ((lo (aref inverse-mass 0)) (hi (aref inverse-mass 0)))
    (declare (type single-float lo hi))
    (dotimes (i n) (setf lo (min lo (aref inverse-mass i)) hi (max hi (aref inverse-mass i))))
    (> hi (* brace-ratio lo))))

(declaim (inline upward-part))
(defun upward-part (x y z up-x up-y up-z)
  "The upward part of the normal X Y Z, UP-X UP-Y UP-Z pointing against gravity. #PRBR4C"
  (declare (type single-float x y z up-x up-y up-z))
  (+ (* x up-x) (* y up-y) (* z up-z)))

(declaim (inline still-row-p))
(defun still-row-p (v o still2)
  "Whether the solver row at O of V moves slower than the sleep speed, STILL2 its square. #PRBR4C"
  (declare (type f32-column v) (type index o) (type single-float still2))
  (< (+ (* (aref v o) (aref v o)) (* (aref v (+ o 1)) (aref v (+ o 1)))
        (* (aref v (+ o 2)) (aref v (+ o 2))))
     still2))

(declaim (inline column-steps with-column-steps))
(defun column-steps (flags)
  "The steps a body has rested on one support straight under it, from its FLAGS word
(+flag-column-steps+). #PRBR4C"
  (declare (type fixnum flags))
  (ldb (byte 6 3) flags))

(defun with-column-steps (count flags)
  "The FLAGS word with its column steps (+flag-column-steps+) set to COUNT. #PRBR4C"
  (declare (type fixnum flags) (type (integer 0 63) count))
  (dpb count (byte 6 3) flags))
;; Marking the braced bodies:1 ends here

;; [[file:../physics.org::#PRBR4C][Marking the braced bodies:2]]
(declaim (inline note-one-sided-support))
(defun note-one-sided-support (braced v row still2)
  "Count a support of the awake ROW held up by something static, and mark it braced when its
solver velocity in V is still (STILL2, the sleep speed squared). #PRBR4C"
  (declare (type fixnum-column braced) (type f32-column v) (type index row) (type single-float still2))
  (let ((o (solver-row row)))
    (declare (type index o))
    (incf (aref braced row) +brace-support+)
    (when (still-row-p v o still2)
      (setf (aref braced row) (logior (aref braced row) +brace-braced+)))))

(declaim (inline note-support))
(defun note-support (braced inverse-mass flags geometry c lower upper rise slop kept)
  "Count a support of the awake row UPPER resting on LOWER through contact C of GEOMETRY, RISE
the upward part of their normal; within 8 degrees of the vertical on a body at least as light,
mark it +brace-on-column+, with +brace-unsettled+ when the contact is deeper than 1.05 SLOPs and
+brace-link+ when LOWER was braced at the step before (KEPT, the pass ran then). #PRBR4C"
  (declare (type fixnum-column braced flags) (type f32-column inverse-mass geometry)
           (type index c lower upper) (type single-float rise slop))
  (incf (aref braced upper) +brace-support+)
  (when (and (> rise 0.99) (>= (aref inverse-mass lower) (aref inverse-mass upper)))
    (setf (aref braced upper)
          (logior (aref braced upper) +brace-on-column+
                  (if (< (contact@ geometry c separation) (* -1.05 slop)) +brace-unsettled+ 0)
                  (if (and kept (logtest (aref flags lower) +flag-braced+)) +brace-link+ 0)))))

(declaim (inline note-pair-supports))
(defun note-pair-supports (braced inverse-mass flags geometry c la lb rise slop kept)
  "Count the supports contact C gives its two awake rows LA and LB, RISE the upward part of the
normal from LA to LB: the upper gains one when the pair stands within 25 degrees of the
vertical (note-support), the lower none; sideways, both. #PRBR4C"
  (declare (type fixnum-column braced flags) (type f32-column inverse-mass geometry)
           (type index c la lb) (type single-float rise slop))
  (cond ((> rise 0.9) (note-support braced inverse-mass flags geometry c la lb rise slop kept))
        ((< rise -0.9) (note-support braced inverse-mass flags geometry c lb la (- rise) slop kept))
        (t (incf (aref braced la) +brace-support+) (incf (aref braced lb) +brace-support+))))

(declaim (inline mark-supports))
(defun mark-supports (contacts m rows braced v inverse-mass flags still2 slop kept up-x up-y up-z)
  "The contacts' pass: for each of the M contacts that carried load, its awake rows in ROWS (as
the colouring found them, -1 for a side that is not an awake body), count the supports and set
the marks of its bodies in BRACED. #PRBR4C"
  (declare (type contact-columns contacts) (type index m) (type fixnum-column rows braced flags)
           (type f32-column v inverse-mass) (type single-float still2 slop up-x up-y up-z))
  (with-contact-columns (geometry) contacts
    (dotimes (c m)
      (when (> (contact@ geometry c normal-impulse) 0.0)
        (let* ((la (aref rows (* 2 c))) (lb (aref rows (1+ (* 2 c))))
               (dyn-a (>= la 0)) (dyn-b (>= lb 0)))
          (declare (type fixnum la lb))
          (cond ((not (eq dyn-a dyn-b)) (note-one-sided-support braced v (if dyn-a la lb) still2))
                (dyn-a (note-pair-supports braced inverse-mass flags geometry c la lb
                                           (upward-part (contact@ geometry c nx) (contact@ geometry c ny)
                                                        (contact@ geometry c nz) up-x up-y up-z)
                                           slop kept))))))))
;; Marking the braced bodies:2 ends here

;; [[file:../physics.org::#PRBR4C][Marking the braced bodies:3]]
(declaim (inline settle-brace-mark))
(defun settle-brace-mark (braced flags v i still2 kept)
  "Settle the mark of awake row I in BRACED: braced, a link of a column, or neither, with
+brace-unsettled+ kept while it counts column steps; write its braced flag and column steps into
FLAGS (counted on from the step before when KEPT). Return whether it counts column steps and
whether it is a link. #PRBR4C"
  (declare (type fixnum-column braced flags) (type f32-column v) (type index i) (type single-float still2))
  (let* ((o (solver-row i))
         (mark (aref braced i))
         (still (still-row-p v o still2))
         (column (and still (logtest mark +brace-on-column+) (= (ash mark -4) 1)))
         (count (if column (min 63 (1+ (if kept (column-steps (aref flags i)) 0))) 0))
         (link (and column (logtest mark +brace-link+) (>= count +column-wait+))))
    (setf (aref braced i)
          (logior (cond (link (logior +brace-braced+ +brace-link+))
                        ((or (logtest mark +brace-braced+)
                             (and kept still (logtest (aref flags i) +flag-braced+)))
                         +brace-braced+)
                        (t 0))
                  (if column (logand mark +brace-unsettled+) 0)))
    (setf (aref flags i) (with-column-steps count (if (logtest (aref braced i) +brace-braced+)
                                                      (logior (aref flags i) +flag-braced+)
                                                      (logandc2 (aref flags i) +flag-braced+))))
    (values column link)))

(declaim (inline settle-brace-marks))
(defun settle-brace-marks (braced flags v n still2 kept)
  "The bodies' pass: settle the mark of each of the N awake rows (settle-brace-mark). Return
whether some body counts column steps (the world's column watch) and whether some body is a
link. #PRBR4C"
  (declare (type fixnum-column braced flags) (type f32-column v) (type index n) (type single-float still2))
  (let ((watch nil) (linked nil))
    (dotimes (i n)
      (multiple-value-bind (column link) (settle-brace-mark braced flags v i still2 kept)
        (when column (setf watch t))
        (when link (setf linked t))))
    (values watch linked)))

(declaim (inline still-braced-sides))
(defun still-braced-sides (contacts m rows braced inverse-mass brace-ratio v up-x up-y up-z)
  "The stilling pass: zero in V the solver velocity of each awake body that one of the M
contacts finds static to a heavier one above it (brace-side), as the one-sided contact takes
it to be: nothing else would stop it rolling out. #PRBR4C"
  (declare (type contact-columns contacts) (type index m) (type fixnum-column rows braced)
           (type f32-column inverse-mass v) (type single-float brace-ratio up-x up-y up-z))
  (with-contact-columns (geometry) contacts
    (dotimes (c m)
      (let ((la (aref rows (* 2 c))) (lb (aref rows (1+ (* 2 c)))))
        (declare (type fixnum la lb))
        (when (and (>= la 0) (>= lb 0))
          (let* ((la la) (lb lb)
                 (side (brace-side braced inverse-mass brace-ratio la lb
                                   (upward-part (contact@ geometry c nx) (contact@ geometry c ny)
                                                (contact@ geometry c nz) up-x up-y up-z))))
            (declare (type index la lb))
            (when side
              (let ((o (solver-row (if (eq side :a) la lb))))
                (fill v 0.0 :start o :end (+ o 6))))))))))

(declaim (inline brace-bodies))
(defun brace-bodies (world contacts m rows braced v inverse-mass flags n still2 slop kept up-x up-y up-z)
  "The bracing pass's first two stages: clear the marks, mark the supports (mark-supports),
settle the marks (settle-brace-marks), and note in WORLD the step of this pass and whether a
column is forming. Return whether some body is a link. #PRBR4C"
  (declare (type fixnum-column braced) (type index n))
  (fill braced 0 :end (1+ n))
  (mark-supports contacts m rows braced v inverse-mass flags still2 slop kept up-x up-y up-z)
  (multiple-value-bind (watch linked) (settle-brace-marks braced flags v n still2 kept)
    (setf (physics-world-braced-step world) (physics-world-step-count world)
          (physics-world-column-watch world) watch)
    linked))
;; Marking the braced bodies:3 ends here

;; [[file:../physics.org::#PRCL0R][Ordering the rows by colour:1]]
(defun order-rows-by-colour (world contact cursor)
  "Write into CONTACT, each colour's run from its start on, WORLD's contacts of that colour: by
colouring piece (the piece of the contact's last awake row), in contact order within a piece;
leave in CURSOR where each colour's contacts end. Each piece writes its own places, so the
pieces run one a worker ([[#SPL1T5]]). #PRCL0R"
  (declare (type fixnum-column contact cursor) #.+kernel-policy+)
  (let* ((m (contact-columns-length (physics-world-contacts world)))
         (n (body-columns-length (physics-world-awake world)))
         (pieces (colour-pieces n))
         (scale (colour-piece-scale n pieces))
         (last (1- pieces))
         (colors (physics-world-contact-colors world))
         (rows (physics-world-contact-rows world))
         (counts (physics-world-colour-counts world))
         (places (physics-world-colour-places world))
         (starts (physics-world-color-starts world)))
    (declare (type index m n pieces last) (type (unsigned-byte 62) scale)
             (type fixnum-column colors rows counts places starts))
    ;; each piece's first place in each colour, after the pieces before it
    (dotimes (color (1+ +physics-max-colors+))
      (let ((at (aref starts color)))
        (declare (type index at))
        (dotimes (p pieces)
          (let ((k (+ (* p (1+ +physics-max-colors+)) color)))
            (setf (aref places k) at)
            (incf at (aref counts k))))
        (setf (aref cursor color) at)))
    ;; one piece, in contact order on one thread; else a share of the pieces a worker
    (when (= pieces 1)
      (dotimes (c m)
        (let ((k (aref colors c)))
          (setf (aref contact (aref places k)) c)
          (incf (aref places k))))
      (return-from order-rows-by-colour))
    (flet ((order-piece (worker count)
             (declare (type fixnum worker count))
             (with-colour-pieces (p0 p1) (pieces worker count)
               ;; a worker without a piece walks no contact
               (dotimes (c (if (< p0 p1) m 0))
                 (let* ((p (colour-piece (max (aref rows (* 2 c)) (aref rows (1+ (* 2 c)))) scale last))
                        (k (+ (* p (1+ +physics-max-colors+)) (aref colors c))))
                   (declare (type index p k))
                   (when (and (<= p0 p) (< p p1))
                     (setf (aref contact (aref places k)) c)
                     (incf (aref places k))))))))
      (declare (dynamic-extent #'order-piece))
      (run-pieces world m :colour-order #'order-piece))))

(declaim (inline pad-colour-rows))
(defun pad-colour-rows (cursor color-starts contact body-a body-b data stride n)
  "Make every row from each colour's CURSOR to the next colour's start (COLOR-STARTS) a padding
row: contact -1, the dummy N on both sides, every float of DATA's main blocks (of STRIDE floats)
zero. #PRCL0R"
  (declare (type fixnum-column cursor color-starts contact body-a body-b) (type f32-column data)
           (type constraint-block-size stride) (type index n))
  (dotimes (color +physics-max-colors+)
    (loop for k of-type index from (aref cursor color) below (aref color-starts (1+ color))
          do (let ((base (+ +constraint-origin+ (* (ash k -3) stride) (logand k 7))))
               (setf (aref contact k) -1 (aref body-a k) n (aref body-b k) n)
               (dotimes (o (floor stride 8)) (setf (aref data (+ base (* 8 o))) 0.0))))))
;; Ordering the rows by colour:1 ends here

;; [[file:../physics.org::#PRF1LL][Filling a row:1]]
(declaim (inline normal-approach))
(defun normal-approach (v va vb kx ky kz x y z)
  "The speed at which the bodies of the solver rows VA and VB of V, side b moved besides by the
box velocity KX KY KZ, approach along the normal X Y Z. #PRF1LL"
  (declare (type f32-column v) (type index va vb) (type single-float kx ky kz x y z))
  (+ (* (- (+ (aref v vb) kx) (aref v va)) x)
     (* (- (+ (aref v (+ vb 1)) ky) (aref v (+ va 1))) y)
     (* (- (+ (aref v (+ vb 2)) kz) (aref v (+ va 2))) z)))

(defmacro fill-short-row ()
  "Fill row K of the constraint buffer for its contact between two awake bodies, neither static
to the other: expanded in the prepare phase's fill. #PRF1LL"
  `(let* ((c (aref contact k))
          (g (geometry-start c)) (base (constraint-base k))
          (la (aref rows (* 2 c))) (lb (aref rows (1+ (* 2 c))))
          (x (contact-at geometry g nx)) (y (contact-at geometry g ny))
          (z (contact-at geometry g nz))
          (kx (contact-at geometry g kvx)) (ky (contact-at geometry g kvy))
          (kz (contact-at geometry g kvz))
          (r-a (aref radius-c la)) (r-b (aref radius-c lb))
          (va (solver-row la)) (vb (solver-row lb)))
     (declare (type index c g base la lb va vb) (type single-float x y z kx ky kz r-a r-b)
              (ignorable va vb kx ky kz))
     (setf (aref body-a k) la (aref body-b k) lb
           (@ nx) x (@ ny) y (@ nz) z (@ ra) r-a (@ rb) r-b
           (@ ima) (aref im-c la) (@ imb) (aref im-c lb)
           (@ iia) (aref ii-c la) (@ iib) (aref ii-c lb)
           (@ separation) (+ (contact-at geometry g separation) slop)
           (@ friction) (fsqrt (* (aref fr-c la) (aref fr-c lb)))
           (@ bias-rate) dyn-bias (@ mass-scale) dyn-mass (@ impulse-scale) dyn-impulse
           (@ normal-impulse) (contact-at geometry g normal-impulse)
           (@ tangent-impulse-1) (contact-at geometry g tangent-impulse-1)
           (@ tangent-impulse-2) (contact-at geometry g tangent-impulse-2))
     ;; the columns of boxes, restitution, rolling resistance and the events, when the world
     ;; has them (spin friction's and the armed speed are zeros here, as the side block starts)
     (if-feature :boxes (setf (@ kvx) kx (@ kvy) ky (@ kvz) kz))
     (if-feature (:or :restitution :contact-events :hit-events) (setf (@ max-normal-impulse) 0.0))
     (if-feature :restitution
       (setf (@ restitution) (max (aref re-c la) (aref re-c lb))))
     (if-feature :rolling-resistance
       (setf (@ rolling-limit) (* (max (aref ro-c la) (aref ro-c lb)) (max r-a r-b))
             (@ rolling-impulse-x) (contact-at geometry g rolling-impulse-x)
             (@ rolling-impulse-y) (contact-at geometry g rolling-impulse-y)
             (@ rolling-impulse-z) (contact-at geometry g rolling-impulse-z)))
     (if-feature (:or :contact-events :hit-events)
       (setf (@ relative-velocity) (normal-approach v va vb kx ky kz x y z)))))
;; Filling a row:1 ends here

;; [[file:../physics.org::#PRF1LL][Filling a row:2]]
(defmacro fill-row-material ()
  "Write the friction, restitution, rolling limit and spin limit of the general path's row:
expanded in fill-row-sides. #PRF1LL"
  `(if (>= b 0)
       (progn
         (setf (@ friction) (fsqrt (* (aref (body-columns-friction buf-a) la)
                                      (aref (body-columns-friction buf-b) lb))))
         (if-feature :restitution
           (setf (@ restitution) (max (aref (body-columns-restitution buf-a) la)
                                      (aref (body-columns-restitution buf-b) lb))))
         (if-feature :rolling-resistance
           (setf (@ rolling-limit) (* (max (aref (body-columns-rolling-resistance buf-a) la)
                                           (aref (body-columns-rolling-resistance buf-b) lb))
                                      (max r-a r-b)))))
       (progn
         (setf (@ friction) (aref (body-columns-friction buf-a) la))
         ;; a spin limit only here, where side b has no radius: the kernels read the spin
         ;; columns only where rb is zero ([[#SSMPYW]])
         (if-feature :friction (setf (@ spin-limit) (* (@ friction) (spin-arm r-a slop))))
         (if-feature :restitution
           (setf (@ restitution) (aref (body-columns-restitution buf-a) la)))
         (if-feature :rolling-resistance
           (setf (@ rolling-limit) (* (aref (body-columns-rolling-resistance buf-a) la) r-a))))))

(defmacro fill-row-softness ()
  "Write the soft coefficients of the general path's row: two-body, or static and stiffened by
its carried load over its effective mass. Expanded in fill-row-sides. #PRF1LL"
  `(let ((load (if two-sided
                   0.0
                   (min load-limit (* (contact-at geometry g normal-impulse) mass-sum load-scale)
                        (* held-mass mass-sum)))))
     (declare (type single-float load))
     (cond ((> load 1.0)
            (setf (@ bias-rate) st-bias (@ mass-scale) st-mass
                  (@ impulse-scale) (/ st-impulse load)))
           (two-sided
            (setf (@ bias-rate) dyn-bias (@ mass-scale) dyn-mass
                  (@ impulse-scale) dyn-impulse))
           (t
            (setf (@ bias-rate) st-bias (@ mass-scale) st-mass
                  (@ impulse-scale) st-impulse)))))

(defmacro fill-row-sides ()
  "Write the general path's radii, inverse masses and inertias, gap, box velocity, material,
spin impulse, approach speed and soft coefficients: expanded in fill-general-row. #PRF1LL"
  `(let* ((r-a (aref (body-columns-radius buf-a) la))
          (r-b (if (>= b 0) (aref (body-columns-radius buf-b) lb) 0.0))
          (im-a (if dyn-a (aref (body-columns-inverse-mass awake) la) 0.0))
          (im-b (if dyn-b (aref (body-columns-inverse-mass awake) lb) 0.0))
          (ii-a (if dyn-a (aref (body-columns-inverse-inertia awake) la) 0.0))
          (ii-b (if dyn-b (aref (body-columns-inverse-inertia awake) lb) 0.0))
          (kx (contact-at geometry g kvx)) (ky (contact-at geometry g kvy)) (kz (contact-at geometry g kvz))
          (mass-sum (+ im-a im-b))
          (va (solver-row (if dyn-a la n)))
          (vb (solver-row (if dyn-b lb n))))
     (declare (type single-float r-a r-b im-a im-b ii-a ii-b kx ky kz) (ignorable va vb kx ky kz))
     (setf (@ ra) r-a (@ rb) r-b
           (@ ima) im-a (@ imb) im-b (@ iia) ii-a (@ iib) ii-b
           (@ separation) (+ (contact-at geometry g separation) slop))
     ;; the box's velocity, until the frame pass resolves it
     (if-feature :boxes (setf (@ kvx) kx (@ kvy) ky (@ kvz) kz))
     (fill-row-material)
     ;; the spin impulse the contact carried out of the last step: zero on every row with a
     ;; radius on side b, whose spin is never solved
     (if-feature :friction (setf (@ spin-impulse) (contact-at geometry g spin-impulse)))
     (if-feature (:or :contact-events :hit-events)
       (setf (@ relative-velocity) (normal-approach v va vb kx ky kz x y z)))
     (fill-row-softness)))

(defmacro fill-general-row ()
  "Fill row K of the constraint buffer for its contact by the general path: each side's set and
row from the handle table, a braced side static: expanded in the prepare phase's fill. #PRF1LL"
  `(let* ((c (aref contact k))
          (g (geometry-start c))
          (base (constraint-base k))
          (a (aref ha c)) (b (aref hb c))
          (set-a (aref sets (handle-index a)))
          (set-b (if (>= b 0) (aref sets (handle-index b)) +set-free+))
          (la (aref locals (handle-index a)))
          (lb (if (>= b 0) (aref locals (handle-index b)) 0))
          (buf-a (if (= set-a +set-awake+) awake sleeping))
          (buf-b (if (= set-b +set-awake+) awake sleeping))
          (sets sets) (locals locals)
          (dyn-a (= set-a +set-awake+)) (dyn-b (= set-b +set-awake+))
          (x (contact-at geometry g nx)) (y (contact-at geometry g ny)) (z (contact-at geometry g nz))
          ;; a braced body is static to a much heavier one above it, as a sleeper is to the
          ;; bodies that lean on it
          (brace (and static dyn-a dyn-b
                      (brace-side braced inverse-mass brace-ratio la lb (upward-part x y z up-x up-y up-z))))
          (dyn-a (and dyn-a (not (eq brace :a))))
          (dyn-b (and dyn-b (not (eq brace :b))))
          (two-sided (and dyn-a dyn-b)))
     (declare (type fixnum a b set-a set-b) (type index c la lb base) (type single-float x y z)
              (type body-columns buf-a buf-b) (type fixnum-column sets locals) (ignorable sets locals))
     (setf (aref body-a k) (if dyn-a la n)
           (aref body-b k) (if dyn-b lb n)
           (@ nx) x (@ ny) y (@ nz) z)
     (fill-row-sides)
     (if-feature (:or :restitution :contact-events :hit-events) (setf (@ max-normal-impulse) 0.0))
     (setf (@ normal-impulse) (contact-at geometry g normal-impulse)
           (@ tangent-impulse-1) (contact-at geometry g tangent-impulse-1)
           (@ tangent-impulse-2) (contact-at geometry g tangent-impulse-2))
     (if-feature :rolling-resistance
       (setf (@ rolling-impulse-x) (contact-at geometry g rolling-impulse-x)
             (@ rolling-impulse-y) (contact-at geometry g rolling-impulse-y)
             (@ rolling-impulse-z) (contact-at geometry g rolling-impulse-z)))))

(defmacro fill-constraint-row ()
  "Fill row K from its contact: by the short path when the world takes it and both of the
contact's bodies have rows, else by the general one. Expanded in the prepare phase's fill, whose
variables it reads. #PRF1LL"
  `(if (let ((c (aref contact k)))
         (and short-path (not static)
              (>= (aref rows (* 2 c)) 0) (>= (aref rows (1+ (* 2 c))) 0)))
       (fill-short-row)
       (fill-general-row)))

(defmacro fill-constraint-rows ()
  "The fill: order the rows by colour, zero the side blocks, fill each colour's rows by the
short or the general path, complete them in the frame pass, and pad each colour. Expanded in
the prepare phase, whose variables it reads. #PRF1LL"
  `(with-contact-columns ((ha handle-a) (hb handle-b) geometry) contacts
     (with-constraint-block (contact body-a body-b) cbuf
       (order-rows-by-colour world contact cursor)
       (with-body-columns ((radius-c radius) (im-c inverse-mass) (ii-c inverse-inertia)
                           (fr-c friction) (re-c restitution) (ro-c rolling-resistance))
           awake
         (declare (ignorable re-c ro-c))
         ;; each row is written from its contact alone, so the rows may be cut into pieces
         ;; of whole blocks, one a worker ([[#SPL1T5]]); a piece first sets its side blocks,
         ;; padding rows' included, to zeros: a row writes only the side columns that may be
         ;; other than zero, the spin limit and impulse of a row with no radius on side b
         ;; ([[#SSMPYW]])
         (flet ((fill-piece (worker count)
                  (declare (type fixnum worker count))
                  (dotimes (color (1+ +physics-max-colors+))
                    (multiple-value-bind (from to)
                        (piece-bounds (aref color-starts color) (aref color-starts (1+ color)) worker count)
                      (declare (type index from to))
                      (when (< from to)
                        (fill (side-floats) 0.0
                              :start (+ +constraint-origin+ (* (floor from 8) (constraint-columns-side-block cbuf)))
                              :end (+ +constraint-origin+ (* (ceiling to 8) (constraint-columns-side-block cbuf)))))
                      (loop for k of-type index from from below (min to (aref cursor color))
                            do (fill-constraint-row))))))
           (declare (dynamic-extent #'fill-piece))
           (run-pieces world (constraint-columns-length cbuf) :fill #'fill-piece)))
       ;; the frames, the box velocities along them and the effective masses, in lanes where
       ;; the family has them
       (physics-prepare-frames (physics-world-kernels world) world)
       (pad-colour-rows cursor color-starts contact body-a body-b data stride n))))
;; Filling a row:2 ends here

;; [[file:../physics.org::#PRSTG6][The prepare phase, stage by stage:1]]
(define-featured-kernel (prepare-phase :features (:body-contacts :boxes :friction :restitution :rolling-resistance :contact-events :hit-events))
    (world)
  "The prepare phase: colour the contacts, then write the constraint buffer in colour order, and load the
awake bodies' velocities into the solver; note the number of colours used in the step's
statistics, and return it. Compiled for fewer features, it writes no column the world's kernels
do not read: restitution's, rolling resistance's, and the approach speed only events read. #PRSTG6"
  (declare #.+kernel-policy+)
  (let* ((h (physics-world-current-h world))
         (contacts (physics-world-contacts world))
         (m (contact-columns-length contacts))
         (awake (physics-world-awake world))
         (sleeping (physics-world-sleeping world))
         (n (body-columns-length awake)))
    (declare (type body-columns awake sleeping) (type contact-columns contacts) (type single-float h)
             (type index m n))
    (ensure-solver-scratch world n m)
    (with-world-parameters ((zeta damping-ratio) slop (load-limit load-stiffening) (brace-ratio brace-mass-ratio)) world
      (let ((short-path *prepare-short-path*)
            (color-count (color-contacts world (if-feature :body-contacts t nil)))
            (hertz (min (f32 (physics-world-contact-hertz world)) (/ 0.25 (the single-float h))))
            (ids (physics-world-ids world))
            (cbuf (physics-world-constraints world))
            (v (physics-world-velocities world))
            (g (fsqrt (+ (expt (physics-world-gravity-x world) 2) (expt (physics-world-gravity-y world) 2)
                         (expt (physics-world-gravity-z world) 2))))
            (held-mass (held-mass-bound world)))
        (declare (type f32-column v)
                 (type single-float slop hertz zeta g load-limit held-mass)
                 (type handle-table ids) (type constraint-columns cbuf))
        (multiple-value-bind (dyn-bias dyn-mass dyn-impulse) (physics-softness hertz zeta h)
          (declare (type single-float dyn-bias dyn-mass dyn-impulse))
          (multiple-value-bind (st-bias st-mass st-impulse) (physics-softness (* 2.0 hertz) zeta h)
            (declare (type single-float st-bias st-mass st-impulse))
            (size-constraint-buffer world cbuf)
            (let ((cursor (make-array (+ +physics-max-colors+ 1) :element-type 'fixnum))
                  (color-starts (physics-world-color-starts world))
                  (sets (handle-table-set ids)) (locals (handle-table-local ids))
                  (braced (physics-world-braced world))
                  ;; each contact's awake rows, as the colouring found them
                  (rows (physics-world-contact-rows world))
                  (still2 (f32 (expt (physics-world-sleep-speed world) 2)))
                  (inverse-mass (body-columns-inverse-mass awake))
                  ;; 1/(|g| h) turns a substep's normal impulse into the mass it holds up
                  (load-scale (if (> g 1e-3) (/ 1.0 (* g h)) 0.0))
                  ;; up, against gravity (zero without gravity)
                  (up-x (if (> g 1e-3) (/ (- (physics-world-gravity-x world)) g) 0.0))
                  (up-y (if (> g 1e-3) (/ (- (physics-world-gravity-y world)) g) 0.0))
                  (up-z (if (> g 1e-3) (/ (- (physics-world-gravity-z world)) g) 0.0)))
              (declare (dynamic-extent cursor) (type fixnum-column sets locals braced rows color-starts)
                       (type single-float brace-ratio still2 load-scale up-x up-y up-z)
                       (type f32-column inverse-mass))
              (replace cursor color-starts)
              ;; a body is braced when it is still and a one-sided contact carried load last step.
              ;; Nothing is braced without gravity: then the scene skips this pass and every test
              ;; of it below. No body is static to another unless one awake body is that many times
              ;; heavier than another, or a column has a link: else the scene skips the tests of
              ;; brace-side below
              (let* ((static (and (> g 1e-3) (plusp n) (masses-span-brace-ratio-p inverse-mass n brace-ratio)))
                     ;; the pass runs at every step where a body may be static to another or a
                     ;; column is forming (a body counting its steps on one support, or a link),
                     ;; and else at every +column-look+th step, which finds a column starting
                     (bracing (and (> g 1e-3) (plusp n)
                                   (or static (physics-world-column-watch world)
                                       (zerop (mod (physics-world-step-count world) +column-look+)))))
                     ;; whether the pass ran at the step before, and the awake bodies' flags
                     (kept (= (physics-world-braced-step world) (1- (physics-world-step-count world))))
                     (flags (body-columns-flags awake)))
                (declare (type fixnum-column flags))
                (when bracing
                  (when (brace-bodies world contacts m rows braced v inverse-mass flags n still2 slop kept
                                      up-x up-y up-z)
                    (setf static t))
                  (when static
                    (still-braced-sides contacts m rows braced inverse-mass brace-ratio v up-x up-y up-z)))
                (fill-constraint-rows)))))
        (setf (step-statistics-colors (world-statistics world)) color-count)
        color-count))))
;; The prepare phase, stage by stage:1 ends here

;; [[file:../physics.org::#PRFRM2][The frame pass:1]]
(defgeneric physics-prepare-frames (kernels world)
  (:documentation "Complete every constraint row the fill wrote: the tangent frame, the box
velocity along the normal and the frame, the effective masses and the first substep's gap. #PRFRM2"))

(declaim (inline moved-gap))
(defun moved-gap (separation nx ny nz ddx ddy ddz kvn elapsed)
  "The gap of a constraint whose prepared gap is SEPARATION along the normal NX NY NZ, after its
bodies' deltas have drawn apart by DDX DDY DDZ and its box has moved at KVN for ELAPSED seconds:
the one formula the relax pass ([[#S0LV3R]]) and the frame pass compute it by. #PRFRM2"
  (declare (type single-float separation nx ny nz ddx ddy ddz kvn elapsed))
  (+ separation (+ (* ddx nx) (* ddy ny) (* ddz nz)) (* kvn elapsed)))

(define-featured-kernel (prepare-frames-range :features (:boxes)) (cbuf start end)
  "Complete constraints START..END of CBUF from their normal, radii, inverse masses and inertias,
and the box velocity held in the KVX, KVY and KVZ columns: the tangent frame t1, t2 (t1 from
the axis least aligned with the normal), the box velocity resolved onto n, t1 and t2, the
normal, tangent and rolling masses (zero where nothing can move), and the gap the first
substep's solve reads. Compiled without boxes, it has no box velocity to resolve. #PRFRM2"
  (declare (type constraint-columns cbuf) (type index start end) #.+kernel-policy+)
  (flet ((inverse (v)
           ;; 1/v where v > 0, else 0: zero where nothing can move
           (declare (type single-float v))
           (if (> v 0.0) (/ 1.0 v) 0.0)))
    (declare (inline inverse))
  (with-constraint-block () cbuf
    (loop for k of-type index from start below end do
      (let* ((base (constraint-base k))
             (x (@ nx)) (y (@ ny)) (z (@ nz))
             (big (> (abs y) 0.9))
             (q (if big (+ (* z z) (* y y)) (+ (* z z) (* x x))))
             ;; a padding row's zero normal: length one, so nothing divides by zero
             (s (/ 1.0 (fsqrt (if (> q 0.0) q 1.0))))
             (ux (if big 0.0 (- (* z s))))
             (uy (if big (* z s) 0.0))
             (uz (if big (- (* y s)) (* x s)))
             (qx (- (* y uz) (* z uy))) (qy (- (* z ux) (* x uz))) (qz (- (* x uy) (* y ux)))
             (ima (@ ima)) (imb (@ imb)) (iia (@ iia)) (iib (@ iib)) (ra (@ ra)) (rb (@ rb))
             (mass-sum (+ ima imb))
             (tangent-sum (+ mass-sum (* iia ra ra) (* iib rb rb)))
             (rolling-sum (+ iia iib)))
        (declare (type index base))
        (setf (@ t1x) ux (@ t1y) uy (@ t1z) uz (@ t2x) qx (@ t2y) qy (@ t2z) qz)
        (if-feature :boxes
          (let ((kx (@ kvx)) (ky (@ kvy)) (kz (@ kvz)))
            (setf (@ kvn) (+ (* kx x) (* ky y) (* kz z))
                  (@ kvt1) (+ (* kx ux) (* ky uy) (* kz uz))
                  (@ kvt2) (+ (* kx qx) (* ky qy) (* kz qz)))))
        (setf ;; the gap the first substep's solve starts from: what the relax pass
              ;; computes ([[#S0LV3R]]), with both deltas and the time elapsed zero
              (@ gap) (moved-gap (@ separation) x y z 0.0 0.0 0.0 (if-feature :boxes (@ kvn) 0.0) 0.0)
              (@ normal-mass) (inverse mass-sum)
              (@ tangent-mass) (inverse tangent-sum)
              (@ rolling-mass) (inverse rolling-sum)))))))

(defmethod physics-prepare-frames ((kernels scalar-kernels) world)
  (let ((cbuf (physics-world-constraints world)))
    (funcall (kernel-variant-prepare-frames (world-kernel-variant world kernels))
             cbuf 0 (constraint-columns-length cbuf))))
;; The frame pass:1 ends here

;; [[file:../physics.org::#G7Q3XR][Soft contacts:1]]
(defun physics-softness (hertz zeta h)
  "The soft-constraint coefficients of a spring of HERTZ and damping ratio ZETA over substep H:
bias rate, mass scale and impulse scale, as three values. #G7Q3XR"
  (declare (type single-float hertz zeta h))
  (if (= hertz 0.0)
      (values 0.0 1.0 0.0)
      (let* ((omega (* 2.0 (f32 pi) hertz))
             (a1 (+ (* 2.0 zeta) (* h omega)))
             (a2 (* h omega a1))
             (a3 (/ 1.0 (+ 1.0 a2))))
        (values (/ omega a1) (* a2 a3) a3))))
;; Soft contacts:1 ends here

;; [[file:../physics.org::#K3RNLS][The kernel entry points, and integration:1]]
(defgeneric physics-integrate-velocities (kernels world h)
  (:documentation "Substep stage 1: add gravity over H to every awake velocity, clamping speed. #K3RNLS"))

(defgeneric physics-warm-start (kernels world)
  (:documentation "Substep stage 2: apply every constraint's carried impulses. #K3RNLS"))

(defgeneric physics-solve-contacts (kernels world inv-h use-bias elapsed)
  (:documentation "Substep stages 3 and 5: one pass over the constraints in colour order, with
the soft bias (solve) or without it (relax). #K3RNLS"))

(defgeneric physics-integrate-positions (kernels world h)
  (:documentation "Substep stage 4: move every awake body's delta by its velocity over H. #K3RNLS"))

(defun check-solver-world (operation world)
  "Signal invalid-physics-parameter naming OPERATION unless WORLD is a physics-world whose
solver arrays hold its awake rows. Called once per phase, outside the hot loops. #K3RNLS"
  (unless (typep world 'physics-world)
    (error 'invalid-physics-parameter :name :world :value world :expected (format nil "a physics-world, in ~(~A~)" operation)))
  (let ((rows (solver-row (1+ (body-columns-length (physics-world-awake world))))))
    (unless (and (<= rows (length (physics-world-velocities world))) (<= rows (length (physics-world-deltas world))))
      (error 'invalid-physics-parameter :world world :name :world :value world
                                        :expected (format nil "a world stepped since its last add, in ~(~A~)" operation)))))

(defun check-solver-number (operation name value low)
  "Signal invalid-physics-parameter naming NAME, an argument of OPERATION, unless VALUE is a
single-float from LOW to 1e7. #K3RNLS"
  (unless (and (typep value 'single-float) (<= low value 1e7))
    (error 'invalid-physics-parameter :name name :value value
                                      :expected (format nil "a single-float from ~A to 1e7, in ~(~A~)" low operation))))

(defmethod physics-integrate-velocities :before ((kernels kernel-family) world h)
  (check-solver-world 'physics-integrate-velocities world)
  (check-solver-number 'physics-integrate-velocities :h h -1e7))

(defmethod physics-warm-start :before ((kernels kernel-family) world)
  (check-solver-world 'physics-warm-start world))

(defmethod physics-solve-contacts :before ((kernels kernel-family) world inv-h use-bias elapsed)
  (check-solver-world 'physics-solve-contacts world)
  (check-solver-number 'physics-solve-contacts :inv-h inv-h 1.0)
  (check-solver-number 'physics-solve-contacts :elapsed elapsed 0.0)
  (unless (typep use-bias 'boolean)
    (error 'invalid-physics-parameter :world world :name :use-bias :value use-bias :expected "T or NIL")))

(defmethod physics-integrate-positions :before ((kernels kernel-family) world h)
  (check-solver-world 'physics-integrate-positions world)
  (check-solver-number 'physics-integrate-positions :h h -1e7))

(defun refuse-kernel-family (kernels operation)
  "Signal invalid-physics-parameter: KERNELS, given to OPERATION, is no kernel family. #K3RNLS"
  (error 'invalid-physics-parameter :name :kernels :value kernels
                                    :expected (format nil "a kernel-family, in ~(~A~)" operation)))

(defmethod physics-integrate-velocities ((kernels t) world h)
  (refuse-kernel-family kernels 'physics-integrate-velocities))

(defmethod physics-warm-start ((kernels t) world)
  (refuse-kernel-family kernels 'physics-warm-start))

(defmethod physics-solve-contacts ((kernels t) world inv-h use-bias elapsed)
  (refuse-kernel-family kernels 'physics-solve-contacts))

(defmethod physics-integrate-positions ((kernels t) world h)
  (refuse-kernel-family kernels 'physics-integrate-positions))

(defun integrate-velocities-range (v start end h gx gy gz max-speed)
  "Add H times gravity to velocity rows START..END of V and clamp their speed to MAX-SPEED. #K3RNLS"
  (declare (type f32-column v) (type index start end) (type single-float h gx gy gz max-speed)
           #.+kernel-policy+)
  (let ((dvx (* h gx)) (dvy (* h gy)) (dvz (* h gz)) (max2 (* max-speed max-speed)))
    (loop for i of-type index from start below end
          for o of-type index = (solver-row i)
          do (store-clamped-velocity v o (+ (aref v o) dvx) (+ (aref v (+ o 1)) dvy) (+ (aref v (+ o 2)) dvz)
                                     max-speed max2))))

(defun integrate-positions-range (v d start end h)
  "Add H times velocity to delta rows START..END of D. #K3RNLS"
  (declare (type f32-column v d) (type index start end) (type single-float h) #.+kernel-policy+)
  (loop for i of-type index from start below end
        for o of-type index = (solver-row i)
        for p of-type index = (delta-row i)
        do (setf (aref d p) (+ (aref d p) (* h (aref v o)))
                 (aref d (+ p 1)) (+ (aref d (+ p 1)) (* h (aref v (+ o 1))))
                 (aref d (+ p 2)) (+ (aref d (+ p 2)) (* h (aref v (+ o 2)))))))
;; The kernel entry points, and integration:1 ends here

;; [[file:../physics.org::#W4RMST][Warm start:1]]
(defmacro with-solver-columns (cbuf &body body)
  "Run BODY over the constraint buffer CBUF: its blocks, its body columns, and (@ COLUMN). #W4RMST"
  `(with-constraint-block (body-a body-b) ,cbuf ,@body))

(define-featured-kernel (warm-start-range :features (:body-contacts :friction :rolling-resistance)) (cbuf v start end)
  "Apply the carried normal, friction and rolling impulses of constraints START..END; compiled
without body contacts, only to body a, for body b is then the dummy row of every constraint. #W4RMST"
  (declare (type constraint-columns cbuf) (type f32-column v) (type index start end) #.+kernel-policy+)
  (with-solver-columns cbuf
    (loop for k of-type index from start below end do
      (let* ((base (constraint-base k))
             (a (solver-row (aref body-a k))) (b (solver-row (aref body-b k)))
             (x (@ nx)) (y (@ ny)) (z (@ nz))
             (l (@ normal-impulse))
             (ma (@ ima)) (mb (@ imb)))
        (declare (type index a b base) (ignorable b mb))
        (if-feature :friction
          (let* ((l1 (@ tangent-impulse-1)) (l2 (@ tangent-impulse-2))
                 (px (+ (* l x) (* l1 (@ t1x)) (* l2 (@ t2x))))
                 (py (+ (* l y) (* l1 (@ t1y)) (* l2 (@ t2y))))
                 (pz (+ (* l z) (* l1 (@ t1z)) (* l2 (@ t2z))))
                 ;; n x P = l1 t2 - l2 t1: the torque arm of the friction part
                 (cx (- (* l1 (@ t2x)) (* l2 (@ t1x))))
                 (cy (- (* l1 (@ t2y)) (* l2 (@ t1y))))
                 (cz (- (* l1 (@ t2z)) (* l2 (@ t1z))))
                 (ia (@ iia)) (ib (@ iib)) (ar (@ ra)) (br (@ rb))
                 ;; the spin impulse about the normal joins the rolling impulse: both are
                 ;; angular. Only a row with no radius on side b has one ([[#SSMPYW]]); any
                 ;; other's is zero, and is not read
                 (sp (if (= br 0.0) (@ spin-impulse) 0.0))
                 (rx (if-feature :rolling-resistance (+ (@ rolling-impulse-x) (* sp x)) (* sp x)))
                 (ry (if-feature :rolling-resistance (+ (@ rolling-impulse-y) (* sp y)) (* sp y)))
                 (rz (if-feature :rolling-resistance (+ (@ rolling-impulse-z) (* sp z)) (* sp z))))
            (declare (ignorable ib br))
            (setf (aref v a) (- (aref v a) (* ma px))
                  (block-ref v a 1) (- (block-ref v a 1) (* ma py))
                  (block-ref v a 2) (- (block-ref v a 2) (* ma pz))
                  (block-ref v a 3) (- (block-ref v a 3) (* ia (+ (* ar cx) rx)))
                  (block-ref v a 4) (- (block-ref v a 4) (* ia (+ (* ar cy) ry)))
                  (block-ref v a 5) (- (block-ref v a 5) (* ia (+ (* ar cz) rz))))
            ;; without body contacts body b is the dummy, whose zeros a zero mass keeps
            (if-feature :body-contacts
              (setf (aref v b) (+ (aref v b) (* mb px))
                    (block-ref v b 1) (+ (block-ref v b 1) (* mb py))
                    (block-ref v b 2) (+ (block-ref v b 2) (* mb pz))
                    (block-ref v b 3) (+ (block-ref v b 3) (* ib (- rx (* br cx))))
                    (block-ref v b 4) (+ (block-ref v b 4) (* ib (- ry (* br cy))))
                    (block-ref v b 5) (+ (block-ref v b 5) (* ib (- rz (* br cz)))))))
          ;; without friction the impulse is along the normal and turns nothing; only rolling
          ;; resistance, when the world has it, turns the bodies
          (let ((px (* l x)) (py (* l y)) (pz (* l z)))
            (setf (aref v a) (- (aref v a) (* ma px))
                  (block-ref v a 1) (- (block-ref v a 1) (* ma py))
                  (block-ref v a 2) (- (block-ref v a 2) (* ma pz)))
            (if-feature :body-contacts
              (setf (aref v b) (+ (aref v b) (* mb px))
                    (block-ref v b 1) (+ (block-ref v b 1) (* mb py))
                    (block-ref v b 2) (+ (block-ref v b 2) (* mb pz))))
            (if-feature :rolling-resistance
              (let ((ia (@ iia)) (ib (@ iib))
                    (rx (@ rolling-impulse-x)) (ry (@ rolling-impulse-y)) (rz (@ rolling-impulse-z)))
                (declare (ignorable ib))
                (setf (block-ref v a 3) (- (block-ref v a 3) (* ia rx))
                      (block-ref v a 4) (- (block-ref v a 4) (* ia ry))
                      (block-ref v a 5) (- (block-ref v a 5) (* ia rz)))
                (if-feature :body-contacts
                  (setf (block-ref v b 3) (+ (block-ref v b 3) (* ib rx))
                        (block-ref v b 4) (+ (block-ref v b 4) (* ib ry))
                        (block-ref v b 5) (+ (block-ref v b 5) (* ib rz))))))))))))
;; Warm start:1 ends here

;; [[file:../physics.org::#S0LV3R][Solve and relax:1]]
(defmacro unswitch-bias ((flag) &body body)
  "BODY twice, once with the symbol BIASED standing for T and once for NIL, chosen by FLAG at run
time: each solve kernel compiles a biased copy and a relaxing copy, and neither tests the flag
per constraint. #S0LV3R"
  `(if ,flag
       (symbol-macrolet ((biased t)) ,@body)
       (symbol-macrolet ((biased nil)) ,@body)))
;; Solve and relax:1 ends here

;; [[file:../physics.org::#S0LGAP][The gap:1]]
(defmacro solve-row-gap ()
  "The current gap of row K: in the solve pass the gap the relax pass kept, in the relax pass
the prepared gap moved by both bodies' deltas and the box's travel, kept in the row for the next
solve. Expanded in solve-range and its copies. #S0LGAP"
  `(if biased
       (@ gap)
       ;; a row's place in the delta array is its place in the velocity
       ;; array ([[#W0RLD7]]), found above
       (let ((da a) (db b))
         (declare (ignorable db))
         (setf (@ gap)
               (moved-gap (@ separation) x y z
                          (- (if-feature :body-contacts (aref d db) 0.0) (aref d da))
                          (- (if-feature :body-contacts (block-ref d db 1) 0.0) (block-ref d da 1))
                          (- (if-feature :body-contacts (block-ref d db 2) 0.0) (block-ref d da 2))
                          (if-feature :boxes (@ kvn) 0.0) elapsed)))))
;; The gap:1 ends here

;; [[file:../physics.org::#S0LNRM][The normal impulse and the bounce:1]]
(defmacro solve-soft-bias ()
  "The bias of row K's normal impulse: a speculative gap S is closed over the substep; in the
solve pass, an overlap is pushed out at the soft bias rate, capped at PUSH-MAX; in the relax
pass, nothing. #S0LNRM"
  `(cond (positive (* s inv-h))
         (biased (let ((soft (* (@ bias-rate) s)) (cap (- push-max)))
                   (if (> soft cap) soft cap)))
         (t 0.0)))

(defmacro solve-impact-bump ()
  "The bounce of row K, a push of its own that makes the pair leave at the speed restitution
gives: in the impact copy, computed for an impact or an armed row; in solve-range, zero, or the
end of the pass at a row that may strike or is armed. Expanded in solve-range and its copies. #S0LNRM"
  `(if-feature :restitution
    (if-feature :impact-part
    (let* ((e (@ restitution))
           (impact (and (> e 0.0) (= mni 0.0) (> new 0.0) (< vn (- threshold)))))
    (if (or impact (and (> (@ armed-speed) 0.0) (not positive)))
      (let* ((sp (if positive s 0.0))
             ;; the change of vn over a substep under gravity
             (dv (* (- (if (> mb 0.0) 1.0 0.0) (if (> ma 0.0) 1.0 0.0))
                    (+ (* hgx x) (* hgy y) (* hgz z))))
             (half (* 0.5 dv))
             ;; vn now, and the speed of the impact when the gap closes
             (c (if biased (- vn half) (+ vn half)))
             (fall (* (* (* 2.0 dv) sp) inv-h))
             (uc (if impact
                     (let ((u2 (- (* c c) fall))) (fsqrt (if (> u2 0.0) u2 0.0)))
                     (@ armed-speed)))
             ;; the leaving speed squared, from here
             (wc2 (+ (* (* e e) (* uc uc)) fall)))
        ;; the events report the approach at impact
        (when impact (setf (@ relative-velocity) (- uc)))
        (if (> 0.0 wc2)
            ;; the rebound would not climb this gap: close it, bounce later
            (progn (setf (@ armed-speed) uc) 0.0)
            (let* ((root (fsqrt (if (> wc2 0.0) wc2 0.0)))
                   (w (if biased (+ root half) (- root half)))
                   (kick (* (@ normal-mass) (- w vn))))
              (when (> kick 0.0) (setf (@ armed-speed) 0.0))
              (if (> kick 0.0) kick 0.0))))
      0.0))
    ;; a row that may strike (it has not pushed yet, approaches faster than
    ;; the threshold and has restitution) or is armed ends the pass here, for
    ;; solve-handing to run the pass with the impact part on it, as it is:
    ;; nothing of it has been written but the kept gap, which that pass
    ;; writes again with the same bits. Only a row with restitution is ever
    ;; armed, so its armed speed is read only then ([[#SSMPYW]])
    (if (and (> (@ restitution) 0.0)
             (or (> (@ armed-speed) 0.0)
                 (and (< vn (- threshold)) (= mni 0.0))))
        (return-from solve-pass k)
        0.0))
    0.0))
;; The normal impulse and the bounce:1 ends here

;; [[file:../physics.org::#S0LFRC][Friction, rolling resistance and spin:1]]
(defmacro solve-rolling-resistance ()
  "Rolling resistance on row K: the rolling impulse inside |R| <= rolling limit times the
normal impulse, applied to the angular velocities WAX..WBZ of the place it is expanded in, one
of the two that solve-friction and solve-frictionless make. #S0LFRC"
  `(let ((rl (@ rolling-limit)))
    (when (> rl 0.0)
      (let* ((rlimit (* rl new)) (rm (@ rolling-mass))
             (rx (@ rolling-impulse-x)) (ry (@ rolling-impulse-y)) (rz (@ rolling-impulse-z))
             (nrx (- rx (* rm (- wbx wax)))) (nry (- ry (* rm (- wby way)))) (nrz (- rz (* rm (- wbz waz))))
             (len2 (+ (* nrx nrx) (* nry nry) (* nrz nrz))))
        (when (> len2 (* rlimit rlimit))
          (let ((scale (/ rlimit (fsqrt len2))))
            (setf nrx (* nrx scale) nry (* nry scale) nrz (* nrz scale))))
        (let ((dx (- nrx rx)) (dy (- nry ry)) (dz (- nrz rz)))
          (setf (@ rolling-impulse-x) nrx (@ rolling-impulse-y) nry (@ rolling-impulse-z) nrz)
          (setf wax (- wax (* iam dx)) way (- way (* iam dy)) waz (- waz (* iam dz))
                wbx (+ wbx (* ibm dx)) wby (+ wby (* ibm dy)) wbz (+ wbz (* ibm dz))))))))

(defmacro solve-spin-friction ()
  "Spin friction on row K: an angular impulse about the normal inside |S| <= spin limit times
the normal impulse, on the angular velocities WAX..WBZ; expanded in solve-friction. #S0LFRC"
  `(let ((sl (if (= br 0.0) (@ spin-limit) 0.0)))
     (when (> sl 0.0)
       (let* ((slimit (* sl new)) (sp (@ spin-impulse))
              (raw (- sp (* (@ rolling-mass)
                            (+ (+ (* (- wbx wax) x) (* (- wby way) y)) (* (- wbz waz) z)))))
              (nsp (if (> raw slimit) slimit (if (> (* slimit -1.0) raw) (* slimit -1.0) raw)))
              (ds (- nsp sp)))
         (setf (@ spin-impulse) nsp
               wax (- wax (* iam (* ds x))) way (- way (* iam (* ds y))) waz (- waz (* iam (* ds z)))
               wbx (+ wbx (* ibm (* ds x))) wby (+ wby (* ibm (* ds y))) wbz (+ wbz (* ibm (* ds z))))))))

(defmacro solve-friction ()
  "Friction on row K inside the cone |l1,l2| <= friction times the normal impulse, from the
relative velocity before the normal impulse; then rolling resistance and spin friction; write
both bodies' velocities. Expanded in solve-range when the world has friction. #S0LFRC"
  `(let* (
          (wax (block-ref v a 3)) (way (block-ref v a 4)) (waz (block-ref v a 5))
          (wbx (if-feature :body-contacts (block-ref v b 3) 0.0))
          (wby (if-feature :body-contacts (block-ref v b 4) 0.0))
          (wbz (if-feature :body-contacts (block-ref v b 5) 0.0))
          (wx (+ (* ar wax) (* br wbx))) (wy (+ (* ar way) (* br wby))) (wz (+ (* ar waz) (* br wbz)))
          (vt1 (- (+ (* dvx ux) (* dvy uy) (* dvz uz) (if-feature :boxes (@ kvt1) 0.0))
                  (+ (* wx qx) (* wy qy) (* wz qz))))
          (vt2 (+ (* dvx qx) (* dvy qy) (* dvz qz) (if-feature :boxes (@ kvt2) 0.0)
                  (+ (* wx ux) (* wy uy) (* wz uz))))
          (l1 (@ tangent-impulse-1)) (l2 (@ tangent-impulse-2))
          (tm (@ tangent-mass))
          (n1 (- l1 (* tm vt1))) (n2 (- l2 (* tm vt2)))
          (limit (* (@ friction) new))
          (len2 (+ (* n1 n1) (* n2 n2)))
          (over (> len2 (* limit limit)))
          ;; inside the cone the scale is 1, and multiplying by 1 changes no bit
          (scale (if over (/ limit (fsqrt len2)) 1.0))
          (n1 (* n1 scale)) (n2 (* n2 scale))
          (d1 (- n1 l1)) (d2 (- n2 l2))
          (px (+ (* d1 ux) (* d2 qx))) (py (+ (* d1 uy) (* d2 qy))) (pz (+ (* d1 uz) (* d2 qz)))
          (cx (- (* d1 qx) (* d2 ux))) (cy (- (* d1 qy) (* d2 uy))) (cz (- (* d1 qz) (* d2 uz)))
          (iar (* iam ar)) (ibr (* ibm br)))
     (setf (@ tangent-impulse-1) n1 (@ tangent-impulse-2) n2)
     (setf (aref v a) (- vax (* ma px)) (block-ref v a 1) (- vay (* ma py)) (block-ref v a 2) (- vaz (* ma pz)))
     (if-feature :body-contacts
       (setf (aref v b) (+ vbx (* mb px)) (block-ref v b 1) (+ vby (* mb py)) (block-ref v b 2) (+ vbz (* mb pz))))
     (let ((wax (- wax (* iar cx))) (way (- way (* iar cy))) (waz (- waz (* iar cz)))
           (wbx (- wbx (* ibr cx))) (wby (- wby (* ibr cy))) (wbz (- wbz (* ibr cz))))
       (if-feature :rolling-resistance (solve-rolling-resistance))
       ;; spin friction: an angular impulse about the normal inside |S| <= spin-limit *
       ;; normal impulse; the rolling mass is the spin's too, for a ball's inertia is
       ;; the same about every axis
       ;; only a row with no radius on side b has a spin limit ([[#SSMPYW]]); any
       ;; other's is zero, and is not read
       (solve-spin-friction)
       (setf (block-ref v a 3) wax (block-ref v a 4) way (block-ref v a 5) waz)
       (if-feature :body-contacts
         (setf (block-ref v b 3) wbx (block-ref v b 4) wby (block-ref v b 5) wbz)))))

(defmacro solve-frictionless ()
  "Write row K's bodies' velocities after the normal impulse, with rolling resistance alone on
the angular ones when the world has it: solve-range without friction. #S0LFRC"
  `(progn
     (setf (aref v a) vax (block-ref v a 1) vay (block-ref v a 2) vaz)
     (if-feature :body-contacts
       (setf (aref v b) vbx (block-ref v b 1) vby (block-ref v b 2) vbz))
     (if-feature :rolling-resistance
       (let ((wax (block-ref v a 3)) (way (block-ref v a 4)) (waz (block-ref v a 5))
             (wbx (if-feature :body-contacts (block-ref v b 3) 0.0))
             (wby (if-feature :body-contacts (block-ref v b 4) 0.0))
             (wbz (if-feature :body-contacts (block-ref v b 5) 0.0)))
         (solve-rolling-resistance)
         (setf (block-ref v a 3) wax (block-ref v a 4) way (block-ref v a 5) waz)
         (if-feature :body-contacts
           (setf (block-ref v b 3) wbx (block-ref v b 4) wby (block-ref v b 5) wbz))))))
;; Friction, rolling resistance and spin:1 ends here

;; [[file:../physics.org::#S0LSTG][The pass, stage by stage:1]]
(define-featured-kernel (solve-range :features (:body-contacts :boxes :friction :rolling-resistance :restitution
                                                 :hit-events :contact-events))
    (cbuf v d start end inv-h use-bias elapsed push-max threshold hgx hgy hgz)
  "One Gauss-Seidel pass over constraints START..END: the soft normal impulse (with the bias
when USE-BIAS), or an impact's bounce (an approach faster than THRESHOLD, under gravity HGX HGY
HGZ times the substep), then Coulomb friction, then rolling resistance. Return END, or the
first row that may strike or is armed, left unsolved for solve-handing. Compiled without body
contacts, it reads and writes body a alone: body b is then the dummy row, all zeros. #S0LSTG"
  (declare (type constraint-columns cbuf) (type f32-column v d) (type index start end)
           (type single-float inv-h elapsed push-max threshold hgx hgy hgz) #.+kernel-policy+
           (ignorable threshold hgx hgy hgz))
  (block solve-pass
  (unswitch-bias (use-bias)
  (with-solver-columns cbuf
    (loop for k of-type index from start below end do
      ;; one straight chain of bindings, a name bound again where its value changes
      (let ((base (constraint-base k)))
       ;; the constraint's own columns are read from the block where they are used
       ;; without body contacts body b is the dummy row of every constraint: its velocities,
       ;; deltas, mass, inertia and radius are zeros, written here as such, and it is not written
       (symbol-macrolet ((x (@ nx)) (y (@ ny)) (z (@ nz)) (ma (@ ima))
                         (mb (if-feature :body-contacts (@ imb) 0.0))
                         (ar (@ ra)) (br (if-feature :body-contacts (@ rb) 0.0)) (iam (@ iia))
                         (ibm (if-feature :body-contacts (@ iib) 0.0))
                         (ux (@ t1x)) (uy (@ t1y)) (uz (@ t1z)) (qx (@ t2x)) (qy (@ t2y)) (qz (@ t2z)))
      (let* ((a (the index (solver-row (aref body-a k))))
             (b (the index (solver-row (aref body-b k))))
             ;; current separation: the prepared gap moved by both deltas and the box's
             ;; travel. The relax pass computes it and keeps it; the next solve, which sees
             ;; the same deltas and the same time, reads it back
             (s (solve-row-gap))
             (vax (aref v a)) (vay (block-ref v a 1)) (vaz (block-ref v a 2))
             (vbx (if-feature :body-contacts (aref v b) 0.0))
             (vby (if-feature :body-contacts (block-ref v b 1) 0.0))
             (vbz (if-feature :body-contacts (block-ref v b 2) 0.0))
             ;; normal: only the linear velocities take part
             (positive (> s 0.0))
             (bias (solve-soft-bias))
             ;; the relative velocity before this constraint's impulses: the normal part
             ;; and, below, friction both read it
             (dvx (- vbx vax)) (dvy (- vby vay)) (dvz (- vbz vaz))
             ;; without boxes the box's velocity is zero, and so written
             (vn (+ (* dvx x) (* dvy y) (* dvz z) (if-feature :boxes (@ kvn) 0.0)))
             (l (@ normal-impulse))
             (raw (if (and biased (not positive))
                      (- l (* (@ normal-mass) (@ mass-scale) (+ vn bias)) (* (@ impulse-scale) l))
                      ;; a speculative gap, or relaxing: the mass scale is 1 and the impulse
                      ;; scale 0, which the other branch would multiply and subtract to the same bits
                      (- l (* (@ normal-mass) (+ vn bias)))))
             (new (if (> raw 0.0) raw 0.0))
             ;; the largest push so far, which only restitution and the events read
             (mni (if-feature (:or :restitution :contact-events :hit-events) (@ max-normal-impulse) 0.0))
             ;; an impact ([[#R3ST1T]]): the first push of a contact approaching faster than
             ;; the threshold; or an armed contact whose gap has closed. Its bounce, the
             ;; impulse that makes the pair leave at the speed restitution gives, is a push
             ;; of its own, not kept in the contact's impulse
             (bump (solve-impact-bump))
             (bounced (> bump 0.0))
             (new (if bounced l new))
             (dl (if bounced bump (- new l)))
             ;; (* ma dl x) is (* (* ma dl) x): forming ma dl once changes no bit
             (madl (* ma dl)) (mbdl (* mb dl))
             (vax (- vax (* madl x))) (vay (- vay (* madl y))) (vaz (- vaz (* madl z)))
             (vbx (+ vbx (* mbdl x))) (vby (+ vby (* mbdl y))) (vbz (+ vbz (* mbdl z))))
        (declare (ignorable b vbx vby vbz mbdl mni))
        (let ((pushed (if bounced bump new)))
          (declare (ignorable pushed))
          (setf (@ normal-impulse) new)
          (if-feature (:or :restitution :contact-events :hit-events)
            (setf (@ max-normal-impulse) (if (> mni pushed) mni pushed))))
        (if-feature :friction
          ;; friction, inside the cone |l1,l2| <= friction * normal impulse; the angular
          ;; velocities are read only now
          (solve-friction)
          ;; without friction the tangent speeds are never read, and the angular velocities
          ;; change only under rolling resistance
          (solve-frictionless))))))))
  end))

(defmacro define-impact-copy (name kernel documentation)
  "Define NAME, described by DOCUMENTATION, as the featured kernel KERNEL compiled with every
feature and with its impact part (the pseudo-feature :impact-part), which KERNEL itself leaves
out: it stops at each row that may strike, for solve-handing to run NAME on it. #S0LSTG"
  (destructuring-bind (operators lambda-list declarations forms tested) (get kernel 'featured-kernel)
    (declare (ignore tested))
    (let ((function `(defun ,name ,lambda-list ,documentation ,@declarations
                       (with-features ,(cons :impact-part +physics-features+) ,@forms))))
      (if operators `(macrolet ,operators ,function) function))))

(define-impact-copy solve-impact-range solve-range
  "One Gauss-Seidel pass over constraints START..END, bouncing impacts ([[#R3ST1T]]): solve-handing
runs it on each row at which solve-range or a variant of it stops. #S0LSTG")

(declaim (inline solve-handing))
(defun solve-handing (solve impact width cbuf v d start end inv-h use-bias elapsed push-max
                      threshold hgx hgy hgz)
  "Run the solve kernel SOLVE over constraints START..END; each time it stops at a row (a block
of WIDTH rows) that may strike, run IMPACT, its copy with the impact part, on that row or block,
and go on with SOLVE after it. #S0LSTG"
  (declare (type index start end width))
  (loop for k of-type index = (funcall solve cbuf v d start end inv-h use-bias elapsed push-max
                                       threshold hgx hgy hgz)
        while (< k end)
        do (funcall impact cbuf v d k (+ k width) inv-h use-bias elapsed push-max threshold hgx hgy hgz)
           (setf start (+ k width))))
;; The pass, stage by stage:1 ends here

;; [[file:../physics.org::#R3ST1T][Restitution at impact:1]]
(defun impact-parameters (world)
  "The restitution threshold of WORLD and its gravity times its substep, as four single-floats:
what a solve pass needs to bounce an impact. #R3ST1T"
  (let ((h (physics-world-current-h world)))
    (declare (type single-float h))
    (values (f32 (physics-world-restitution-threshold world))
            (* h (physics-world-gravity-x world)) (* h (physics-world-gravity-y world))
            (* h (physics-world-gravity-z world)))))
;; Restitution at impact:1 ends here

;; [[file:../physics.org::#SC4L4R][The scalar family:1]]
(defmethod physics-integrate-velocities ((kernels scalar-kernels) world h)
  (let ((awake (physics-world-awake world)))
    (if (pushes-live-p world)
        ;; forces or gravity scales are in use ([[#F0RC3S]])
        (integrate-pushed-velocities-range (physics-world-velocities world) (checked-pushes world)
                                           (body-columns-handle awake) (body-columns-inverse-mass awake)
                                           0 (body-columns-length awake) h
                                           (physics-world-gravity-x world) (physics-world-gravity-y world)
                                           (physics-world-gravity-z world) (f32 (physics-world-max-speed world)))
        (integrate-velocities-range (physics-world-velocities world) 0 (body-columns-length awake) h
                                    (physics-world-gravity-x world) (physics-world-gravity-y world)
                                    (physics-world-gravity-z world) (f32 (physics-world-max-speed world))))))

(defmethod physics-warm-start ((kernels scalar-kernels) world)
  (let ((cbuf (physics-world-constraints world)))
    (if (solving-joints world)
        ;; joints are solved colour by colour with the contacts ([[#J0FAML]])
        (warm-start-with-joints kernels world)
        (funcall (kernel-variant-warm-start (world-kernel-variant world kernels))
                 cbuf (physics-world-velocities world) 0 (constraint-columns-length cbuf)))))

(defmethod physics-solve-contacts ((kernels scalar-kernels) world inv-h use-bias elapsed)
  (let ((cbuf (physics-world-constraints world)))
    (if (solving-joints world)
        (solve-with-joints kernels world inv-h use-bias elapsed)
        (multiple-value-bind (threshold hgx hgy hgz) (impact-parameters world)
          (solve-handing (kernel-variant-solve (world-kernel-variant world kernels)) 'solve-impact-range 1
                         cbuf (physics-world-velocities world) (physics-world-deltas world)
                         0 (constraint-columns-length cbuf) inv-h use-bias elapsed
                         (f32 (physics-world-push-max world)) threshold hgx hgy hgz)))))

(defmethod physics-integrate-positions ((kernels scalar-kernels) world h)
  (integrate-positions-range (physics-world-velocities world) (physics-world-deltas world) 0
                             (body-columns-length (physics-world-awake world)) h))
;; The scalar family:1 ends here

;; [[file:../physics.org::#J0STOR][Joints are rows, named by handles:1]]
(defconstant +joint-point+ 0 "Joint kind: a point joint, its two anchors held together. #J0STOR")

(defconstant +joint-distance+ 1 "Joint kind: a distance joint, its two anchors held at a length. #J0STOR")

(defconstant +joint-spring+ 1 "Joint flag: its length is a spring of its hertz and damping ratio. #J0STOR")

(defconstant +joint-slack+ 2 "Joint flag: no length of its own (a rope): only its limits hold. #J0STOR")

(defconstant +joint-lower+ 4 "Joint flag: its minimum length holds. #J0STOR")

(defconstant +joint-upper+ 8 "Joint flag: its maximum length holds. #J0STOR")

(defconstant +flag-jointed+ 512
  "Body flag: the body has a joint, so it sleeps only with its joint group ([[#J0SL3P]]). #J0STOR")

(defconstant +joint-anchor-reach+ 2.0
  "How many of its body's radii an anchor may lie from the body's centre. #J0STOR")

(defconstant +physics-min-joint-length+ 0.005 "The shortest length, m, a distance joint may be given. #J0STOR")

(defconstant +physics-max-joint-length+ 1000.0 "The longest length, m, a distance joint may be given. #J0STOR")
(defconstant +physics-min-joint-hertz+ 0.001 "The lowest hertz above 0 a joint's spring may be given. #J0STOR")

(defconstant +physics-max-break-force+ 1e12 "The largest break force, N, a joint may be given. #J0STOR")

(defconstant +event-joint-break+ 10 "Event code of :joint-break. #J0STOR")

(defconstant +event-joint-removed+ 11 "Event code of :joint-removed. #J0STOR")

(define-physics-layout joint-columns
  "The joints of a world, a row each: what the caller gave, the impulses carried between substeps
and steps, and what the step's prepare writes for the substeps. #J0STOR"
  (kind fixnum) (flags fixnum) (handle fixnum) (body-a fixnum) (body-b fixnum)
  (ax single-float) (ay single-float) (az single-float)
  (bx single-float) (by single-float) (bz single-float)
  (rest-length single-float) (min-length single-float) (max-length single-float)
  (hertz single-float) (damping-ratio single-float) (break-force single-float)
  ;; carried: a point joint's impulse; a distance joint's length, lower and upper impulses
  (impulse-x single-float) (impulse-y single-float) (impulse-z single-float)
  ;; written by the prepare, read by the substeps
  (row-a fixnum) (row-b fixnum)
  (rax single-float) (ray single-float) (raz single-float)
  (rbx single-float) (rby single-float) (rbz single-float)
  (sx single-float) (sy single-float) (sz single-float)
  (ima single-float) (imb single-float) (iia single-float) (iib single-float)
  (k11 single-float) (k12 single-float) (k13 single-float)
  (k22 single-float) (k23 single-float) (k33 single-float)
  (bias-rate single-float) (mass-scale single-float) (impulse-scale single-float)
  (limit-scale single-float))

(defstruct (joint-set (:constructor %make-joint-set (ids)) (:copier nil))
  "Everything a world keeps for its joints: the rows, their handle table, and by body slot the
joint groups' parents, each body's count of joints and the passes' marks; the stiff softness
of this step's limits, and the step's colouring of its joints. #J0STOR"
  (rows (make-joint-columns) :type joint-columns)
  (ids nil :type handle-table)
  (parent (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (counts (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (marks (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (groups-stale nil)
  (limit-bias 0.0 :type single-float)
  (limit-mass 1.0 :type single-float)
  ;; the step's colouring of the joints to solve ([[#J0COLR]]): each joint's colour by row, the
  ;; rows in colour order, each colour's run of them, the rows the sort into that order writes,
  ;; and whether the substeps are solving them
  (colors (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (order (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (scratch nil)
  (color-starts (make-array (+ +physics-max-colors+ 2) :element-type 'fixnum :initial-element 0)
   :type fixnum-column)
  (solving nil)
  ;; whether this step's substeps turned the jointed spheres' orientations ([[#J0TURN]])
  (turned nil))
;; Joints are rows, named by handles:1 ends here

;; [[file:../physics.org::#J0STOR][Joints are rows, named by handles:2]]
(declaim (inline group-root))
(defun group-root (parent slot)
  "The root of SLOT's joint group in PARENT, halving the path to it on the way: the groups of [[#J0SL3P]]. #J0STOR"
  (declare (type fixnum-column parent) (type index slot))
  (loop until (= (aref parent slot) slot)
        do (setf (aref parent slot) (aref parent (aref parent slot))
                 slot (aref parent slot)))
  slot)

(defun ensure-joint-set (world)
  "WORLD's joint set, made with its first joint: its handles carry the world's tag, and the world
records joint events from then on. #J0STOR"
  (or (physics-world-joints world)
      (progn
        (setf (slot-value world 'event-mask)
              (logior (world-event-mask world) (ash 1 +event-joint-break+) (ash 1 +event-joint-removed+)))
        (setf (physics-world-joints world)
              (%make-joint-set (%make-handle-table :tag (handle-table-tag (physics-world-ids world))))))))

(defun ensure-joint-slots (world set)
  "Grow SET's columns by body slot to cover every slot of WORLD's handle table; a new slot is a
group of its own. #J0STOR"
  (let ((need (length (handle-table-set (physics-world-ids world))))
        (old (length (joint-set-parent set))))
    (when (< old need)
      (let ((parent (make-array need :element-type 'fixnum)))
        (dotimes (i need) (setf (aref parent i) i))
        (replace parent (joint-set-parent set))
        (setf (joint-set-parent set) parent
              (joint-set-counts set) (fixnum-column-copy (joint-set-counts set) need old)
              (joint-set-marks set) (make-array need :element-type 'fixnum :initial-element 0))
        (fill (joint-set-counts set) 0 :start old)))
    set))

(defun joint-handle-status (world joint)
  "NIL when JOINT names a live joint of WORLD, else why not (:malformed :unissued :foreign
:removed), as handle-status answers for bodies. #J0STOR"
  (if (not (and (typep joint 'fixnum) (>= joint 0) (logbitp +handle-joint-bit+ joint)))
      :malformed
      (let ((h (ldb (byte +handle-joint-bit+ 0) joint))
            (set (physics-world-joints world)))
        (cond (set (handle-status (joint-set-ids set) h))
              ((/= (handle-tag h) (handle-table-tag (physics-world-ids world)))
               (if (tag-issued-p (handle-tag h)) :foreign :unissued))
              (t :removed)))))

(defun resolve-joint (world joint)
  "The row of JOINT in WORLD's joints, or a stale-physics-handle error. #J0STOR"
  (let ((status (joint-handle-status world joint)))
    (when status (error 'stale-physics-handle :world world :handle joint :reason status))
    (aref (handle-table-local (joint-set-ids (physics-world-joints world)))
          (handle-index (ldb (byte +handle-joint-bit+ 0) joint)))))
;; Joints are rows, named by handles:2 ends here

;; [[file:../physics.org::#J0STOR][Joints are rows, named by handles:3]]
(declaim (inline rotate-by))
(defun rotate-by (qw qx qy qz x y z)
  "X Y Z turned by the unit quaternion QW QX QY QZ, as three values: with t = 2 u x v for u the
quaternion's vector part, v + w t + u x t. #J0STOR"
  (declare (type single-float qw qx qy qz x y z))
  (let ((tx (* 2.0 (- (* qy z) (* qz y))))
        (ty (* 2.0 (- (* qz x) (* qx z))))
        (tz (* 2.0 (- (* qx y) (* qy x)))))
    (values (+ x (* qw tx) (- (* qy tz) (* qz ty)))
            (+ y (* qw ty) (- (* qz tx) (* qx tz)))
            (+ z (* qw tz) (- (* qx ty) (* qy tx))))))

(defun body-anchor (world handle lx ly lz)
  "The world point of the anchor LX LY LZ, in the frame of HANDLE's live body, as three values. #J0STOR"
  (multiple-value-bind (set row) (resolve-handle world handle)
    (with-body-columns (x y z qw qx qy qz) (set-buffer world set)
      (multiple-value-bind (rx ry rz) (rotate-by (aref qw row) (aref qx row) (aref qy row) (aref qz row)
                                                 (f32 lx) (f32 ly) (f32 lz))
        (values (+ (aref x row) rx) (+ (aref y row) ry) (+ (aref z row) rz))))))

(defun checked-anchor (world name anchor)
  "ANCHOR, a list of three finite numbers, as three single-floats; else the error naming NAME. #J0STOR"
  (unless (and (listp anchor) (eql 3 (ignore-errors (list-length anchor))))
    (error 'invalid-physics-parameter :world world :name name :value anchor :expected "a list of three numbers"))
  (values (finite-f32 name (first anchor) world) (finite-f32 name (second anchor) world)
          (finite-f32 name (third anchor) world)))

(defun check-anchor-reach (world name x y z radius)
  "Signal invalid-physics-parameter naming NAME unless the local anchor X Y Z lies within
+joint-anchor-reach+ radii, RADIUS each, of its body's centre. #J0STOR"
  (let ((reach (* +joint-anchor-reach+ radius)))
    (unless (and (<= (abs x) reach) (<= (abs y) reach) (<= (abs z) reach)
                 (<= (+ (* x x) (* y y) (* z z)) (* reach reach)))
      (error 'invalid-physics-parameter :world world :name name :value (list x y z)
                                        :expected (format nil "within ~A radii (~,3F m) of its body's centre"
                                                          +joint-anchor-reach+ reach)))))

(defun set-body-flag (world handle flag on)
  "Set FLAG in the flags of HANDLE's live body when ON, else clear it. #J0STOR"
  (multiple-value-bind (set row) (resolve-handle world handle)
    (let ((flags (body-columns-flags (set-buffer world set))))
      (setf (aref flags row) (if on (logior (aref flags row) flag) (logandc2 (aref flags row) flag))))))
;; Joints are rows, named by handles:3 ends here

;; [[file:../physics.org::#J0STOR][Joints are rows, named by handles:4]]
(defun add-physics-joint (world kind body-a body-b &key (anchor-a '(0 0 0)) anchor-b length min-length
                                                       max-length rope (hertz 0) (damping-ratio 0) break-force)
  "Join BODY-A to BODY-B (a handle, or NIL for a fixed point of the world) by a joint of KIND,
:point or :distance, and return its handle. ANCHOR-A is a point in BODY-A's frame; ANCHOR-B one
in BODY-B's frame or, without BODY-B, a point of the world (by default where ANCHOR-A is now). A
distance joint holds LENGTH (by default the anchors' distance now): stiffly, or as a spring of
HERTZ and DAMPING-RATIO when HERTZ is above 0, or, with ROPE, only as a maximum; MIN-LENGTH and
MAX-LENGTH bound it. A joint whose substep impulse exceeds BREAK-FORCE times the substep breaks.
Everything is checked first: a mistake signals a physics-error naming its argument and changes
nothing. #J0STOR"
  (check-idle world 'add-physics-joint)
  (require-physics-feature world :joints 'add-physics-joint)
  (unless (member kind '(:point :distance))
    (error 'invalid-physics-parameter :world world :name :kind :value kind :expected ":point or :distance"))
  (resolve-handle world body-a)
  (when body-b
    (resolve-handle world body-b)
    (when (= body-a body-b)
      (error 'invalid-physics-parameter :world world :name :body-b :value body-b
                                        :expected "a body other than BODY-A, or NIL for a fixed point")))
  (multiple-value-bind (ax ay az) (checked-anchor world :anchor-a anchor-a)
    (check-anchor-reach world :anchor-a ax ay az (physics-body-radius world body-a))
    (multiple-value-bind (pax pay paz) (body-anchor world body-a ax ay az)
      (multiple-value-bind (bx by bz)
          (if (or body-b anchor-b) (checked-anchor world :anchor-b (or anchor-b '(0 0 0))) (values pax pay paz))
        (if body-b
            (check-anchor-reach world :anchor-b bx by bz (physics-body-radius world body-b))
            (progn (check-coordinate :anchor-b bx world) (check-coordinate :anchor-b by world)
                   (check-coordinate :anchor-b bz world)))
        (multiple-value-bind (pbx pby pbz) (if body-b (body-anchor world body-b bx by bz) (values bx by bz))
          (let* ((distance (f32 (sqrt (+ (expt (- pbx pax) 2) (expt (- pby pay) 2) (expt (- pbz paz) 2)))))
                 (point (eq kind :point))
                 (hz (let ((hz (ranged-f32 :hertz hertz 0 1000 world)))
                       (when (< 0.0 hz +physics-min-joint-hertz+)
                         (error 'invalid-physics-parameter :world world :name :hertz :value hertz
                                                           :expected (format nil "0, or from ~A to 1000" +physics-min-joint-hertz+)))
                       hz))
                 (zeta (ranged-f32 :damping-ratio damping-ratio 0 1000 world))
                 (low +physics-min-joint-length+) (high +physics-max-joint-length+)
                 (rest (cond (point 0.0)
                             (length (ranged-f32 :length length low high world))
                             (t (ranged-f32 :length distance low high world))))
                 (least (and min-length (ranged-f32 :min-length min-length low high world)))
                 (most (cond (max-length (ranged-f32 :max-length max-length (or least low) high world))
                             (rope (max rest (or least 0.0)))))
                 (force (and break-force (ranged-f32 :break-force break-force 0 +physics-max-break-force+ world))))
            (when (and point (or length min-length max-length rope))
              (error 'invalid-physics-parameter :world world :name (cond (length :length) (min-length :min-length)
                                                                         (max-length :max-length) (t :rope))
                                                :value (or length min-length max-length rope)
                                                :expected "NIL: a point joint has no length"))
            (when (and force (not (plusp force)))
              (error 'invalid-physics-parameter :world world :name :break-force :value break-force
                                                :expected "a positive force, or NIL for none"))
            (let ((count (if (physics-world-joints world)
                             (joint-columns-length (joint-set-rows (physics-world-joints world)))
                             0)))
              (when (>= count (1- (ash 1 +handle-index-bits+)))
                (error 'physics-budget-exceeded :world world :operation 'add-physics-joint :resource :joints
                                                :requested (1+ count) :budget (1- (ash 1 +handle-index-bits+)))))
            ;; everything is checked: from here on the world changes
            (let* ((set (ensure-joint-slots world (ensure-joint-set world)))
                   (rows (joint-set-rows set))
                   (row (joint-columns-append rows))
                   (handle (logior (ash 1 +handle-joint-bit+)
                                   (handle-table-allocate (joint-set-ids set) +set-awake+ row))))
              (with-joint-columns ((k kind) (f flags) (h handle) (a body-a) (b body-b) (jax ax) (jay ay) (jaz az)
                                   (jbx bx) (jby by) (jbz bz) rest-length min-length max-length (jh hertz)
                                   (jz damping-ratio) (jf break-force) row-a)
                  rows
                (setf (aref k row) (if point +joint-point+ +joint-distance+)
                      (aref f row) (logior (if (and (not point) (> hz 0.0) (not rope)) +joint-spring+ 0)
                                           (if rope +joint-slack+ 0)
                                           (if least +joint-lower+ 0)
                                           (if most +joint-upper+ 0))
                      (aref h row) handle (aref a row) body-a (aref b row) (or body-b +no-body+)
                      (aref jax row) ax (aref jay row) ay (aref jaz row) az
                      (aref jbx row) bx (aref jby row) by (aref jbz row) bz
                      (aref rest-length row) rest (aref min-length row) (or least 0.0)
                      (aref max-length row) (or most 0.0) (aref jh row) hz (aref jz row) zeta
                      (aref jf row) (or force 0.0) (aref row-a row) -1))
              (note-joint-bodies world set body-a body-b 1)
              (wake-handle world body-a)
              (when body-b (wake-handle world body-b))
              handle)))))))
;; Joints are rows, named by handles:4 ends here

;; [[file:../physics.org::#J0STOR][Joints are rows, named by handles:5]]
(defun note-joint-bodies (world set body-a body-b change)
  "Count a joint more (CHANGE 1) or less (-1) at BODY-A and at BODY-B (a handle or NIL), flag a
body +flag-jointed+ while its count is above zero, and join their groups when a joint is added
(a removal marks the groups stale, to be found again from the joints left). #J0STOR"
  (ensure-joint-slots world set)
  (let ((counts (joint-set-counts set)))
    (dolist (h (if body-b (list body-a body-b) (list body-a)))
      (when (null (handle-status (physics-world-ids world) h))
        (let ((slot (handle-index h)))
          (incf (aref counts slot) change)
          (set-body-flag world h +flag-jointed+ (plusp (aref counts slot))))))
    (if (and (plusp change) body-b (not (joint-set-groups-stale set)))
        (let ((parent (joint-set-parent set)))
          (setf (aref parent (group-root parent (handle-index body-a))) (group-root parent (handle-index body-b))))
        (when (minusp change) (setf (joint-set-groups-stale set) t)))))

(defun remove-joint-row (world set row)
  "Remove the joint at ROW of SET: its bodies count it no more, its handle goes stale, and the
last row fills its place. #J0STOR"
  (let* ((rows (joint-set-rows set)) (ids (joint-set-ids set))
         (handle (aref (joint-columns-handle rows) row))
         (b (aref (joint-columns-body-b rows) row)))
    (note-joint-bodies world set (aref (joint-columns-body-a rows) row) (if (= b +no-body+) nil b) -1)
    (let ((moved (joint-columns-swap-remove rows row)))
      (when (>= moved 0)
        (setf (aref (handle-table-local ids) (handle-index (aref (joint-columns-handle rows) row))) row)))
    (handle-table-release ids (ldb (byte +handle-joint-bit+ 0) handle))
    handle))

(defun remove-physics-joint (world joint)
  "Remove JOINT from WORLD and wake its bodies; JOINT goes stale. #J0STOR"
  (check-idle world 'remove-physics-joint)
  (let* ((row (resolve-joint world joint))
         (set (physics-world-joints world))
         (a (aref (joint-columns-body-a (joint-set-rows set)) row))
         (b (aref (joint-columns-body-b (joint-set-rows set)) row)))
    (remove-joint-row world set row)
    (wake-handle world a)
    (unless (= b +no-body+) (wake-handle world b))
    (values)))

(defun remove-body-joints (world handle)
  "Remove every joint of HANDLE's body, each with a :joint-removed event naming both bodies and
carrying the joint's handle. #J0STOR"
  (let* ((set (physics-world-joints world)) (rows (joint-set-rows set)))
    (when (plusp (aref (joint-set-counts (ensure-joint-slots world set)) (handle-index handle)))
      (loop for row from (1- (joint-columns-length rows)) downto 0
            do (let ((a (aref (joint-columns-body-a rows) row)) (b (aref (joint-columns-body-b rows) row)))
                 (when (or (= a handle) (= b handle))
                   (push-event world +event-joint-removed+ a b 0.0 0.0 0.0 0.0
                               (aref (joint-columns-handle rows) row))
                   (remove-joint-row world set row)))))))
;; Joints are rows, named by handles:5 ends here

;; [[file:../physics.org::#J0STOR][Joints are rows, named by handles:6]]
(defun physics-joint-alive-p (world joint)
  "True when JOINT names a joint of WORLD that has not been removed or broken. #J0STOR"
  (check-world world 'physics-joint-alive-p)
  (null (joint-handle-status world joint)))

(defun physics-world-joint-count (world)
  "How many joints WORLD holds. #J0STOR"
  (check-world world 'physics-world-joint-count)
  (let ((set (physics-world-joints world)))
    (if set (joint-columns-length (joint-set-rows set)) 0)))

(defun physics-joint-bodies (world joint)
  "The two bodies JOINT joins, as two values: handles, the second NIL for a fixed point. #J0STOR"
  (check-world world 'physics-joint-bodies)
  (let* ((row (resolve-joint world joint)) (rows (joint-set-rows (physics-world-joints world)))
         (b (aref (joint-columns-body-b rows) row)))
    (values (aref (joint-columns-body-a rows) row) (if (= b +no-body+) nil b))))

(defun joint-anchor-points (world row)
  "The world points of the two anchors of the joint at ROW, as six values. #J0STOR"
  (with-joint-columns (body-a body-b ax ay az bx by bz) (joint-set-rows (physics-world-joints world))
    (multiple-value-bind (pax pay paz) (body-anchor world (aref body-a row) (aref ax row) (aref ay row) (aref az row))
      (multiple-value-bind (pbx pby pbz)
          (if (= (aref body-b row) +no-body+)
              (values (aref bx row) (aref by row) (aref bz row))
              (body-anchor world (aref body-b row) (aref bx row) (aref by row) (aref bz row)))
        (values pax pay paz pbx pby pbz)))))

(defun physics-joint-length (world joint)
  "The distance, m, between JOINT's two anchors where its bodies are now. #J0STOR"
  (check-world world 'physics-joint-length)
  (multiple-value-bind (ax ay az bx by bz) (joint-anchor-points world (resolve-joint world joint))
    (sqrt (+ (expt (- bx ax) 2) (expt (- by ay) 2) (expt (- bz az) 2)))))

(defun joint-row-impulse (rows row)
  "The size of the impulse, N s, the joint at ROW of ROWS applied in its last substep: a point
joint's vector, a distance joint's along its axis. #J0STOR"
  (with-joint-columns (kind impulse-x impulse-y impulse-z) rows
    (let ((x (aref impulse-x row)) (y (aref impulse-y row)) (z (aref impulse-z row)))
      (if (= (aref kind row) +joint-point+)
          (sqrt (+ (* x x) (* y y) (* z z)))
          (abs (- (+ x y) z))))))

(defun physics-joint-impulse (world joint)
  "The size of the impulse, N s, JOINT applied in its last substep (its force times the substep). #J0STOR"
  (check-world world 'physics-joint-impulse)
  (joint-row-impulse (joint-set-rows (physics-world-joints world)) (resolve-joint world joint)))

(defun validate-joints (world fail)
  "Walk WORLD's joints, calling FAIL with a message for the first broken invariant: each row's
handle is live and forwards to it, live slots and rows agree, each joint's bodies are live and
two, and each body's count of joints and its jointed flag are right. #J0STOR"
  (let ((set (physics-world-joints world)))
    (when set
      (let* ((rows (joint-set-rows set)) (ids (joint-set-ids set)) (bodies (physics-world-ids world))
             (counts (make-hash-table)) (live 0))
        (dotimes (row (joint-columns-length rows))
          (let* ((h (aref (joint-columns-handle rows) row)) (status (joint-handle-status world h))
                 (a (aref (joint-columns-body-a rows) row)) (b (aref (joint-columns-body-b rows) row)))
            (when status (funcall fail "joint row ~D holds handle ~D, which is ~(~A~)" row h status))
            (unless (= row (aref (handle-table-local ids) (handle-index (ldb (byte +handle-joint-bit+ 0) h))))
              (funcall fail "joint ~D forwards to another row than ~D" h row))
            (when (handle-status bodies a) (funcall fail "joint ~D names body ~D, which is ~(~A~)" h a (handle-status bodies a)))
            (unless (or (= b +no-body+) (null (handle-status bodies b)))
              (funcall fail "joint ~D names body ~D, which is ~(~A~)" h b (handle-status bodies b)))
            (when (= a b) (funcall fail "joint ~D joins body ~D to itself" h a))
            (incf (gethash a counts 0))
            (unless (= b +no-body+) (incf (gethash b counts 0)))))
        (dotimes (slot (handle-table-count ids))
          (unless (= (aref (handle-table-set ids) slot) +set-free+) (incf live)))
        (unless (= live (joint-columns-length rows))
          (funcall fail "~D live joint slots but ~D joint rows" live (joint-columns-length rows)))
        (loop for (set-code buffer) in (list (list +set-awake+ (physics-world-awake world))
                                             (list +set-sleeping+ (physics-world-sleeping world)))
              do (dotimes (row (body-columns-length buffer))
                   (let* ((h (aref (body-columns-handle buffer) row))
                          (n (gethash h counts 0))
                          (counted (if (< (handle-index h) (length (joint-set-counts set)))
                                       (aref (joint-set-counts set) (handle-index h)) 0)))
                     (unless (= n counted)
                       (funcall fail "body ~D has ~D joints, counted as ~D" h n counted))
                     (unless (eq (plusp n) (logtest +flag-jointed+ (aref (body-columns-flags buffer) row)))
                       (funcall fail "body ~D in set ~D has ~D joints and its jointed flag ~:[clear~;set~]"
                                h set-code n (logtest +flag-jointed+ (aref (body-columns-flags buffer) row)))))))))))
;; Joints are rows, named by handles:6 ends here

;; [[file:../physics.org::#J0STIF][Stiff, and how stiff:1]]
(defconstant +joint-damping-ratio+ 1.0
  "The damping ratio of a stiff joint: critical. #J0STIF")

(defun joint-stiffness (world h)
  "The frequency and damping ratio of a stiff joint of WORLD over substep H, as two values: a
third of the substep rate, and +joint-damping-ratio+. #J0STIF"
  (declare (ignore world))
  (values (/ 1.0 (* 3.0 h)) +joint-damping-ratio+))

(defvar *joint-relax-passes* 2
  "How many relax passes a substep gives its joints: one with the contacts, the others over the
joints alone (relax-joints). #J0STIF")
;; Stiff, and how stiff:1 ends here

;; [[file:../physics.org::#J0STIF][Stiff, and how stiff:2]]
(defun relax-joints (set v d inv-h kernels)
  "The joints' relax passes of a substep after the one they share with the contacts: the joints
of SET solved this step, colour by colour and the overflow colour last, without bias, over the
solver's velocities V and deltas D, *joint-relax-passes* less one times, by the solve of the
family KERNELS (joint-kernels). #J0STIF"
  (declare (type joint-set set) (type f32-column v d) (type single-float inv-h))
  (let ((js (joint-set-color-starts set))
        (solve (nth-value 1 (joint-kernels kernels))))
    (declare (type fixnum-column js) (type function solve))
    (loop repeat (1- (the fixnum *joint-relax-passes*))
          do (dotimes (c (1+ +physics-max-colors+))
               (let ((s (aref js c)) (e (aref js (1+ c))))
                 (declare (type index s e))
                 (when (< s e) (funcall solve set v d inv-h nil s e)))))))
;; Stiff, and how stiff:2 ends here

;; [[file:../physics.org::#J0STIF][Stiff, and how stiff:3]]
(defun spring-softness (hertz zeta h)
  "The soft coefficients of a spring joint of HERTZ and damping ratio ZETA over substep H: those of
physics-softness for the damping ratio less the h omega / 2 that solving the spring implicitly
adds, and no less than zero. #J0STIF"
  (declare (type single-float hertz zeta h))
  (physics-softness hertz (max 0.0 (- zeta (* 0.5 h 2.0 (f32 pi) hertz))) h))
;; Stiff, and how stiff:3 ends here

;; [[file:../physics.org::#J0PREP][The prepare:1]]
(defun place-joint-levers (rows dummy sets locals awake sleeping)
  "Note, for each joint of ROWS, its two solver rows (DUMMY for a fixed point or a sleeping
second body) and its levers, its anchors turned by its bodies' orientations (none for a fixed
point); or -1 as its first row when its first body is not awake. SETS and LOCALS are the body
handle table's, AWAKE and SLEEPING the body buffers. Return how many joints are to be solved.
#J0PREP"
  (declare (type joint-columns rows) (type index dummy) (type fixnum-column sets locals)
           (type body-columns awake sleeping) #.+kernel-policy+)
  (let ((active 0))
    (declare (type index active))
    (with-joint-columns (body-a body-b ax ay az bx by bz row-a row-b rax ray raz rbx rby rbz) rows
      (with-body-columns (qw qx qy qz) awake
        (with-body-columns ((sqw qw) (sqx qx) (sqy qy) (sqz qz)) sleeping
          (dotimes (j (joint-columns-length rows))
            (let* ((ha (aref body-a j)) (hb (aref body-b j))
                   (la (aref locals (handle-index ha)))
                   (b-set (if (= hb +no-body+) 0 (aref sets (handle-index hb))))
                   (lb (if (= hb +no-body+) -1 (aref locals (handle-index hb)))))
              (declare (type fixnum ha hb la b-set lb))
              (if (/= (aref sets (handle-index ha)) +set-awake+)
                  (setf (aref row-a j) -1)
                  (let ((b-moves (= b-set +set-awake+)))
                    (incf active)
                    (setf (aref row-a j) la (aref row-b j) (if b-moves lb dummy))
                    (multiple-value-bind (rx ry rz)
                        (rotate-by (aref qw la) (aref qx la) (aref qy la) (aref qz la) (aref ax j) (aref ay j) (aref az j))
                      (setf (aref rax j) rx (aref ray j) ry (aref raz j) rz))
                    (multiple-value-bind (rx ry rz)
                        (cond ((< lb 0) (values 0.0 0.0 0.0))
                              (b-moves (rotate-by (aref qw lb) (aref qx lb) (aref qy lb) (aref qz lb)
                                                  (aref bx j) (aref by j) (aref bz j)))
                              (t (rotate-by (aref sqw lb) (aref sqx lb) (aref sqy lb) (aref sqz lb)
                                            (aref bx j) (aref by j) (aref bz j))))
                      (setf (aref rbx j) rx (aref rby j) ry (aref rbz j) rz)))))))))
    active))

(defun place-joint-masses (rows dummy locals awake sleeping)
  "Note, for each joint of ROWS placed by place-joint-levers, its bodies' masses (none for a
fixed point or a sleeper; DUMMY is the row of both) and the separation of its bodies' centres,
or of its centre and its fixed point, at the step's start. LOCALS is the body handle table's,
AWAKE and SLEEPING the body buffers. #J0PREP"
  (declare (type joint-columns rows) (type index dummy) (type fixnum-column locals)
           (type body-columns awake sleeping) #.+kernel-policy+)
  (with-joint-columns (body-b bx by bz row-a row-b sx sy sz ima imb iia iib) rows
    (with-body-columns (x y z inverse-mass inverse-inertia) awake
      (with-body-columns ((s-x x) (s-y y) (s-z z)) sleeping
        (dotimes (j (joint-columns-length rows))
          (let ((la (aref row-a j)) (lb (aref row-b j)) (hb (aref body-b j)))
            (declare (type fixnum la lb hb))
            (when (>= la 0)
              (setf (aref ima j) (aref inverse-mass la) (aref iia j) (aref inverse-inertia la))
              (multiple-value-bind (px py pz)
                  (cond ((= hb +no-body+) (values (aref bx j) (aref by j) (aref bz j)))
                        ((/= lb dummy) (values (aref x lb) (aref y lb) (aref z lb)))
                        (t (let ((sl (aref locals (handle-index hb))))
                             (values (aref s-x sl) (aref s-y sl) (aref s-z sl)))))
                (setf (aref imb j) (if (or (= hb +no-body+) (= lb dummy)) 0.0 (aref inverse-mass lb))
                      (aref iib j) (if (or (= hb +no-body+) (= lb dummy)) 0.0 (aref inverse-inertia lb))
                      (aref sx j) (+ (- (aref x la)) px) (aref sy j) (+ (- (aref y la)) py)
                      (aref sz j) (+ (- (aref z la)) pz)))))))))
  nil)
;; The prepare:1 ends here

;; [[file:../physics.org::#J0PREP][The prepare:2]]
(declaim (inline joint-effective-mass))
(defun joint-effective-mass (rows j cx cy cz)
  "Write the effective mass of the placed joint J of ROWS for its levers as they are: a point
joint's matrix K of the anchors, inverted (its six entries), or a distance joint's axial mass
along the anchors' separation CX CY CZ. #J0PREP"
  (declare (type joint-columns rows) (type index j) (type single-float cx cy cz) #.+kernel-policy+)
  (with-joint-columns (kind rax ray raz rbx rby rbz ima imb iia iib k11 k12 k13 k22 k23 k33) rows
    (let* ((m (+ (aref ima j) (aref imb j))) (ia (aref iia j)) (ib (aref iib j))
           (ax (aref rax j)) (ay (aref ray j)) (az (aref raz j))
           (bx (aref rbx j)) (by (aref rby j)) (bz (aref rbz j)))
      (declare (type single-float m ia ib ax ay az bx by bz))
      (if (= (aref kind j) +joint-point+)
          (let* ((a11 (+ m (* ia (+ (* ay ay) (* az az))) (* ib (+ (* by by) (* bz bz)))))
                 (a22 (+ m (* ia (+ (* ax ax) (* az az))) (* ib (+ (* bx bx) (* bz bz)))))
                 (a33 (+ m (* ia (+ (* ax ax) (* ay ay))) (* ib (+ (* bx bx) (* by by)))))
                 (a12 (- (+ (* ia ax ay) (* ib bx by))))
                 (a13 (- (+ (* ia ax az) (* ib bx bz))))
                 (a23 (- (+ (* ia ay az) (* ib by bz))))
                 (c11 (- (* a22 a33) (* a23 a23))) (c12 (- (* a13 a23) (* a12 a33)))
                 (c13 (- (* a12 a23) (* a13 a22))) (c22 (- (* a11 a33) (* a13 a13)))
                 (c23 (- (* a12 a13) (* a11 a23))) (c33 (- (* a11 a22) (* a12 a12)))
                 (det (+ (* a11 c11) (* a12 c12) (* a13 c13)))
                 (inv (if (> det 0.0) (/ 1.0 det) 0.0)))
            (setf (aref k11 j) (* c11 inv) (aref k12 j) (* c12 inv) (aref k13 j) (* c13 inv)
                  (aref k22 j) (* c22 inv) (aref k23 j) (* c23 inv) (aref k33 j) (* c33 inv)))
          (let* ((len (fsqrt (+ (* cx cx) (* cy cy) (* cz cz))))
                 (s (if (> len 1e-9) (/ 1.0 len) 0.0))
                 (nx (* cx s)) (ny (* cy s)) (nz (* cz s))
                 (ax1 (- (* ay nz) (* az ny))) (ay1 (- (* az nx) (* ax nz))) (az1 (- (* ax ny) (* ay nx)))
                 (bx1 (- (* by nz) (* bz ny))) (by1 (- (* bz nx) (* bx nz))) (bz1 (- (* bx ny) (* by nx)))
                 (k (+ m (* ia (+ (* ax1 ax1) (* ay1 ay1) (* az1 az1)))
                       (* ib (+ (* bx1 bx1) (* by1 by1) (* bz1 bz1))))))
            (setf (aref k11 j) (if (> k 0.0) (/ 1.0 k) 0.0)))))))

(defun joint-soft-coefficients (rows j h stiff-bias stiff-mass stiff-impulse)
  "Write the soft coefficients of the placed joint J of ROWS over substep H: its own hertz's (a
spring's by spring-softness), or the stiff ones, STIFF-BIAS STIFF-MASS STIFF-IMPULSE; and the
stiff impulse scale of its limits. #J0PREP"
  (declare (type joint-columns rows) (type index j) (type single-float h stiff-bias stiff-mass stiff-impulse)
           #.+kernel-policy+)
  (with-joint-columns (flags hertz damping-ratio bias-rate mass-scale impulse-scale limit-scale) rows
    (setf (aref limit-scale j) stiff-impulse)
    (if (> (aref hertz j) 0.0)
        (multiple-value-bind (br ms is)
            (if (logtest (aref flags j) +joint-spring+)
                (spring-softness (aref hertz j) (aref damping-ratio j) h)
                (physics-softness (aref hertz j) (aref damping-ratio j) h))
          (setf (aref bias-rate j) br (aref mass-scale j) ms (aref impulse-scale j) is))
        (setf (aref bias-rate j) stiff-bias (aref mass-scale j) stiff-mass (aref impulse-scale j) stiff-impulse))))
;; The prepare:2 ends here

;; [[file:../physics.org::#J0PREP][The prepare:3]]
(defun prepare-joints (world h)
  "Write, for every joint of WORLD whose first body is awake, what the substeps of H read, stage
by stage, each a loop over the rows, which keeps the columns one loop reads and writes at once
few: the solver rows and the turned levers (place-joint-levers), the masses and the separation
(place-joint-masses), the effective mass (joint-effective-mass), the soft coefficients
(joint-soft-coefficients); then colour the joints (color-joints). Return the joint set when
some joint is to be solved, else NIL. #J0PREP"
  (let* ((set (physics-world-joints world))
         (rows (and set (joint-set-rows set)))
         (ids (physics-world-ids world))
         (awake (physics-world-awake world)) (sleeping (physics-world-sleeping world))
         (dummy (body-columns-length awake))
         (active 0))
    (declare (type fixnum active))
    (when set (setf (joint-set-solving set) nil))
    (when (and set (plusp (joint-columns-length rows)))
      (multiple-value-bind (stiff-hertz stiff-zeta) (joint-stiffness world h)
        (multiple-value-bind (stiff-bias stiff-mass stiff-impulse) (physics-softness stiff-hertz stiff-zeta h)
          (setf (joint-set-limit-bias set) stiff-bias (joint-set-limit-mass set) stiff-mass)
          (setf active (place-joint-levers rows dummy (handle-table-set ids) (handle-table-local ids) awake sleeping))
          (place-joint-masses rows dummy (handle-table-local ids) awake sleeping)
          (with-joint-columns (row-a sx sy sz rax ray raz rbx rby rbz) rows
            (dotimes (j (joint-columns-length rows))
              (when (>= (aref row-a j) 0)
                (joint-effective-mass rows j (- (+ (aref sx j) (aref rbx j)) (aref rax j))
                                      (- (+ (aref sy j) (aref rby j)) (aref ray j))
                                      (- (+ (aref sz j) (aref rbz j)) (aref raz j)))))
            (dotimes (j (joint-columns-length rows))
              (when (>= (aref row-a j) 0)
                (joint-soft-coefficients rows j h stiff-bias stiff-mass stiff-impulse))))))
      (when (plusp active) (color-joints world set))
      (setf (joint-set-solving set) (plusp active)))
    (and (plusp active) set)))
;; The prepare:3 ends here

;; [[file:../physics.org::#J0COLR][Coloured with the contacts:1]]
(defun color-joints (world set)
  "Colour the joints of SET prepared for this step on the colour masks the contacts' colouring
left ([[#SSMPYW]]): first each joint of two awake bodies takes the lowest of colours 0-19 free at
both, then each joint of one awake body takes, at it, the highest free colour among those in use,
or failing that the lowest free colour; a joint that fits nowhere goes to the overflow colour 24.
Then write SET's order, its prepared rows colour by colour and in row order within a colour,
the others after them, and its colour starts, and sort its rows into that order. #J0COLR"
  (declare #.+kernel-policy+)
  (let* ((rows (joint-set-rows set)) (n (joint-columns-length rows))
         (masks (physics-world-color-masks world))
         (contact-starts (physics-world-color-starts world))
         (dummy (body-columns-length (physics-world-awake world)))
         (used 0))
    (declare (type fixnum-column masks contact-starts) (type index n dummy) (type (unsigned-byte 32) used))
    (when (< (length (joint-set-colors set)) n)
      (setf (joint-set-colors set) (make-array (max 16 (* 2 n)) :element-type 'fixnum :initial-element 0)
            (joint-set-order set) (make-array (max 16 (* 2 n)) :element-type 'fixnum :initial-element 0)))
    (let ((colors (joint-set-colors set)) (order (joint-set-order set)) (starts (joint-set-color-starts set))
          (row-a (joint-columns-row-a rows)) (row-b (joint-columns-row-b rows)))
      (declare (type fixnum-column colors order starts row-a row-b))
      ;; the colours the contacts use
      (dotimes (c +physics-max-colors+)
        (when (< (aref contact-starts c) (aref contact-starts (1+ c)))
          (setf used (logior used (ash 1 c)))))
      (flet ((take (j color la lb)
               ;; joint J takes COLOR, marked at the rows LA and LB (-1 for none)
               (declare (type index j) (type fixnum color la lb))
               (setf (aref colors j) color)
               (when (< color +physics-max-colors+)
                 (setf used (logior used (ash 1 color))
                       (aref masks la) (logior (aref masks la) (ash 1 color)))
                 (when (>= lb 0) (setf (aref masks lb) (logior (aref masks lb) (ash 1 color)))))))
        (declare (inline take))
        ;; pass one: joints of two awake bodies, the lowest colour free at both
        (dotimes (j n)
          (let ((la (aref row-a j)) (lb (aref row-b j)))
            (declare (type fixnum la lb))
            (cond ((< la 0) (setf (aref colors j) -2))
                  ((= lb dummy) (setf (aref colors j) -1))
                  (t (let ((free (logand (lognot (logior (aref masks la) (aref masks lb)))
                                         (1- (ash 1 +physics-dynamic-colors+)))))
                       (take j (if (zerop free) +physics-max-colors+ (lowest-bit free)) la lb))))))
        ;; pass two: joints of one awake body, as late among the used colours as it allows
        (dotimes (j n)
          (when (= (aref colors j) -1)
            (let* ((la (aref row-a j))
                   (free (logand (lognot (aref masks la)) (1- (ash 1 +physics-max-colors+)))))
              (declare (type index la) (type (unsigned-byte 32) free))
              (take j (cond ((plusp (logand free used)) (highest-bit (logand free used)))
                            ((plusp free) (lowest-bit free))
                            (t +physics-max-colors+))
                    la -1)))))
      ;; each colour's count, its end by the running sum, and its rows placed from the end back
      (fill starts 0)
      (dotimes (j n) (when (>= (aref colors j) 0) (incf (aref starts (aref colors j)))))
      (loop with at of-type index = 0
            for c from 0 to +physics-max-colors+
            do (incf at (aref starts c)) (setf (aref starts c) at)
            finally (setf (aref starts (1+ +physics-max-colors+)) at))
      (loop for j of-type fixnum from (1- n) downto 0
            for c of-type fixnum = (aref colors j)
            when (>= c 0)
              do (setf (aref order (decf (aref starts c))) j))
      ;; the joints not solved this step after them, in row order
      (loop with at of-type index = (aref starts (1+ +physics-max-colors+))
            for j of-type index below n
            when (< (aref colors j) 0)
              do (setf (aref order at) j) (incf at))
      (sort-joint-rows set))))

(defun sort-joint-rows (set)
  "Put the rows of SET in its colour order, when they are not yet, so that each colour's joints
are consecutive rows: each joint's handle forwarded to its new row, its colour noted by row, and
the order the rows' own again. #J0COLR"
  (declare #.+kernel-policy+)
  (let* ((rows (joint-set-rows set)) (n (joint-columns-length rows))
         (order (joint-set-order set)) (colors (joint-set-colors set)) (starts (joint-set-color-starts set)))
    (declare (type fixnum-column order colors starts) (type index n))
    (unless (loop for i of-type index below n always (= (aref order i) i))
      ;; the colours by row are the places' scratch: each row's place in the order
      (dotimes (i n) (setf (aref colors (aref order i)) i))
      (joint-columns-permute rows (or (joint-set-scratch set) (setf (joint-set-scratch set) (make-joint-columns)))
                             colors n)
      (let ((local (handle-table-local (joint-set-ids set))) (handle (joint-columns-handle rows)))
        (declare (type fixnum-column local handle))
        (dotimes (r n)
          (setf (aref local (handle-index (ldb (byte +handle-joint-bit+ 0) (aref handle r)))) r
                (aref order r) r)))
      (fill colors -2 :end n)
      (dotimes (c (1+ +physics-max-colors+))
        (loop for r of-type index from (aref starts c) below (aref starts (1+ c))
              do (setf (aref colors r) c))))
    set))
;; Coloured with the contacts:1 ends here

;; [[file:../physics.org::#J0TURN][Levers that turn in the substeps:1]]
(defmacro turn-row-orientation (v i hw qw qx qy qz)
  "Turn row I's orientation, in the columns QW QX QY QZ, by its spin in the solver's velocities V
over the time whose half is HW: q + hw (0, w) q, normalised. Expanded in place by the substeps'
turn of the jointed spheres and by the finalize's fold ([[#F1NAL5]]), so both turn a row to the
same bits. #J0TURN"
  `(let* ((o (solver-row ,i)) (hw ,hw)
          (ax (aref ,v (+ o 3))) (ay (aref ,v (+ o 4))) (az (aref ,v (+ o 5)))
          (w0 (aref ,qw ,i)) (x0 (aref ,qx ,i)) (y0 (aref ,qy ,i)) (z0 (aref ,qz ,i))
          (nw (- w0 (* hw (+ (* ax x0) (* ay y0) (* az z0)))))
          (nx (+ x0 (* hw (+ (* ax w0) (- (* ay z0) (* az y0))))))
          (ny (+ y0 (* hw (+ (* ay w0) (- (* az x0) (* ax z0))))))
          (nz (+ z0 (* hw (+ (* az w0) (- (* ax y0) (* ay x0))))))
          (s (/ 1.0 (fsqrt (+ (* nw nw) (* nx nx) (* ny ny) (* nz nz))))))
     (declare (type index o) (type single-float hw ax ay az w0 x0 y0 z0 nw nx ny nz s))
     (setf (aref ,qw ,i) (* nw s) (aref ,qx ,i) (* nx s) (aref ,qy ,i) (* ny s) (aref ,qz ,i) (* nz s))))

(defun turn-jointed-orientations (set awake v h)
  "Turn the orientation of each awake jointed sphere of AWAKE by its spin in V over the substep
H, q + h/2 (0, w) q normalised, after the positions integrate, and note in SET that this step's
substeps turned them, so that the finalize phase does not turn them again. #J0TURN"
  (declare (type joint-set set) (type body-columns awake) (type f32-column v) (type single-float h)
           #.+kernel-policy+)
  (setf (joint-set-turned set) t)
  (let ((hw (* 0.5 h)))
    (with-body-columns (qw qx qy qz flags) awake
      (dotimes (i (body-columns-length awake))
        (when (= (logand (aref flags i) (logior +flag-jointed+ +flag-box-shape+)) +flag-jointed+)
          (turn-row-orientation v i hw qw qx qy qz)))))
  nil)

(defun turn-joint-levers (set awake)
  "Turn the levers of each joint of SET solved this step to its awake bodies' orientations in
AWAKE as the substeps have turned them: the first bodies' levers, then the second bodies', two
loops that each touch few joint columns ([[#J0PREP]]'s prepare). #J0TURN"
  (declare (type joint-set set) (type body-columns awake) #.+kernel-policy+)
  (let ((rows (joint-set-rows set))
        (n (aref (joint-set-color-starts set) (1+ +physics-max-colors+))))
    (declare (type index n))
    (with-body-columns (qw qx qy qz) awake
      (with-joint-columns (ax ay az row-a rax ray raz) rows
        (dotimes (j n)
          (let ((la (aref row-a j)))
            (declare (type index la))
            (multiple-value-bind (x y z)
                (rotate-by (aref qw la) (aref qx la) (aref qy la) (aref qz la) (aref ax j) (aref ay j) (aref az j))
              (setf (aref rax j) x (aref ray j) y (aref raz j) z)))))
      (with-joint-columns (bx by bz row-b rbx rby rbz imb) rows
        (dotimes (j n)
          ;; a fixed point has no lever, a sleeper keeps its own
          (when (> (aref imb j) 0.0)
            (let ((lb (aref row-b j)))
              (declare (type index lb))
              (multiple-value-bind (x y z)
                  (rotate-by (aref qw lb) (aref qx lb) (aref qy lb) (aref qz lb) (aref bx j) (aref by j) (aref bz j))
                (setf (aref rbx j) x (aref rby j) y (aref rbz j) z)))))))
    nil))

(defun joints-turned-p (world)
  "Whether WORLD's last substeps turned its jointed spheres' orientations, which the finalize
phase then leaves as they are; the note is taken back as it is read. #J0TURN"
  (let ((set (physics-world-joints world)))
    (and set (joint-set-turned set) (progn (setf (joint-set-turned set) nil) t))))
;; Levers that turn in the substeps:1 ends here

;; [[file:../physics.org::#J0FAML][One text for every family:1]]
(defgeneric joint-kernels (kernels)
  (:documentation "The warm start and the solve of KERNELS' joints, as two functions of the
arguments of warm-start-joints and solve-joints: the scalar ones, or a wide family's lanes
([[#J0LANE]]). #J0FAML"))

(defmethod joint-kernels ((kernels scalar-kernels)) (values #'warm-start-joints #'solve-joints))

(defun solving-joints (world)
  "The joint set whose joints WORLD's substeps are solving, or NIL: what the kernel families'
constraint passes test once a call. #J0FAML"
  (let ((set (physics-world-joints world)))
    (and set (joint-set-solving set) set)))

(defmacro do-constraint-colours ((start end world &key settle joints) colour-form overflow-form)
  "Run, for each colour of WORLD's constraints in turn, the form of JOINTS, (SET FORM), with SET
bound to the joint set and START END to the colour's run of its rows, when the substeps solve
joints and the colour has some (SETTLE first), then COLOUR-FORM with START END bound to the
colour's run of the constraint buffer, when it has one; then SETTLE, then the overflow colour's
joints and OVERFLOW-FORM. #J0FAML"
  (let ((starts (gensym "STARTS")) (c (gensym "C")) (set (or (first joints) (gensym "SET"))))
    `(let ((,starts (physics-world-color-starts ,world))
           (,set (solving-joints ,world)))
       (declare (type fixnum-column ,starts))
       (flet ((joint-run (,c)
                (declare (type fixnum ,c))
                (let* ((js (joint-set-color-starts ,set))
                       (,start (aref js ,c)) (,end (aref js (1+ ,c))))
                  (declare (type fixnum-column js) (type index ,start ,end))
                  (when (< ,start ,end) ,@(when settle (list settle)) ,(second joints)))))
         (declare (inline joint-run))
         (dotimes (,c +physics-max-colors+)
           (when ,set (joint-run ,c))
           (let ((,start (aref ,starts ,c)) (,end (aref ,starts (1+ ,c))))
             (when (< ,start ,end) ,colour-form)))
         ,@(when settle (list settle))
         (when ,set (joint-run +physics-max-colors+))
         (let ((,start (aref ,starts +physics-max-colors+)) (,end (aref ,starts (1+ +physics-max-colors+))))
           (when (< ,start ,end) ,overflow-form))))))

(defun warm-start-with-joints (kernels world)
  "The scalar family's warm start in a step that solves joints: colour by colour, the colour's
joints, then its contacts, as the wide families run them. #J0FAML"
  (let ((cbuf (physics-world-constraints world))
        (v (physics-world-velocities world)) (d (physics-world-deltas world))
        (warm (kernel-variant-warm-start (world-kernel-variant world kernels))))
    (do-constraint-colours (s e world :joints (set (warm-start-joints set v d s e)))
      (funcall warm cbuf v s e)
      (funcall warm cbuf v s e))))

(defun solve-with-joints (kernels world inv-h use-bias elapsed)
  "The scalar family's solve or relax pass in a step that solves joints: colour by colour, the
colour's joints, then its contacts, as the wide families run them. #J0FAML"
  (let ((cbuf (physics-world-constraints world))
        (v (physics-world-velocities world)) (d (physics-world-deltas world))
        (push-max (f32 (physics-world-push-max world)))
        (solve (kernel-variant-solve (world-kernel-variant world kernels))))
    (multiple-value-bind (threshold hgx hgy hgz) (impact-parameters world)
      (flet ((contacts (s e)
               (solve-handing solve 'solve-impact-range 1 cbuf v d s e inv-h use-bias elapsed push-max
                              threshold hgx hgy hgz)))
        (do-constraint-colours (s e world :joints (set (solve-joints set v d inv-h use-bias s e)))
          (contacts s e)
          (contacts s e))))))
;; One text for every family:1 ends here

;; [[file:../physics.org::#J0PTDS][A point joint and a distance joint:1]]
(defmacro with-joint-row ((v d j) &body body)
  "Run BODY for the prepared joint J, its columns bound by with-joint-columns, over the solver's velocities V and deltas D, with:
OA OB the two solver rows, MA MB IA IB the masses, AX .. BZ the levers, CX CY CZ the separation
now, (relative-velocity) the anchors' relative velocity as three values and (push! PX PY PZ) the
impulse P applied to the second body and -P to the first. CX CY CZ are read where they are
used, so a pass that needs no separation, a point joint's relax or warm start, reads no delta. #J0PTDS"
  `(let* ((la (aref row-a ,j)) (lb (aref row-b ,j))
          (oa (solver-row la)) (ob (solver-row lb)) (da (delta-row la)) (db (delta-row lb))
          (ma (aref ima ,j)) (mb (aref imb ,j)) (ia (aref iia ,j)) (ib (aref iib ,j))
          (ax (aref rax ,j)) (ay (aref ray ,j)) (az (aref raz ,j))
          (bx (aref rbx ,j)) (by (aref rby ,j)) (bz (aref rbz ,j)))
     (declare (type index la lb oa ob da db) (type single-float ma mb ia ib ax ay az bx by bz)
              (ignorable da db))
     (symbol-macrolet ((cx (+ (aref sx ,j) (- (aref ,d db) (aref ,d da)) (- bx ax)))
                       (cy (+ (aref sy ,j) (- (aref ,d (+ db 1)) (aref ,d (+ da 1))) (- by ay)))
                       (cz (+ (aref sz ,j) (- (aref ,d (+ db 2)) (aref ,d (+ da 2))) (- bz az))))
     (flet ((relative-velocity ()
              (let ((wax (aref ,v (+ oa 3))) (way (aref ,v (+ oa 4))) (waz (aref ,v (+ oa 5)))
                    (wbx (aref ,v (+ ob 3))) (wby (aref ,v (+ ob 4))) (wbz (aref ,v (+ ob 5))))
                (values (- (+ (aref ,v ob) (- (* wby bz) (* wbz by))) (+ (aref ,v oa) (- (* way az) (* waz ay))))
                        (- (+ (aref ,v (+ ob 1)) (- (* wbz bx) (* wbx bz))) (+ (aref ,v (+ oa 1)) (- (* waz ax) (* wax az))))
                        (- (+ (aref ,v (+ ob 2)) (- (* wbx by) (* wby bx))) (+ (aref ,v (+ oa 2)) (- (* wax ay) (* way ax)))))))
            (push! (px py pz)
              (declare (type single-float px py pz))
              (setf (aref ,v oa) (- (aref ,v oa) (* ma px))
                    (aref ,v (+ oa 1)) (- (aref ,v (+ oa 1)) (* ma py))
                    (aref ,v (+ oa 2)) (- (aref ,v (+ oa 2)) (* ma pz))
                    (aref ,v (+ oa 3)) (- (aref ,v (+ oa 3)) (* ia (- (* ay pz) (* az py))))
                    (aref ,v (+ oa 4)) (- (aref ,v (+ oa 4)) (* ia (- (* az px) (* ax pz))))
                    (aref ,v (+ oa 5)) (- (aref ,v (+ oa 5)) (* ia (- (* ax py) (* ay px)))))
              ;; the dummy row, a fixed point's or a sleeper's, stays zero
              (when (> mb 0.0)
                (setf (aref ,v ob) (+ (aref ,v ob) (* mb px))
                      (aref ,v (+ ob 1)) (+ (aref ,v (+ ob 1)) (* mb py))
                      (aref ,v (+ ob 2)) (+ (aref ,v (+ ob 2)) (* mb pz))
                      (aref ,v (+ ob 3)) (+ (aref ,v (+ ob 3)) (* ib (- (* by pz) (* bz py))))
                      (aref ,v (+ ob 4)) (+ (aref ,v (+ ob 4)) (* ib (- (* bz px) (* bx pz))))
                      (aref ,v (+ ob 5)) (+ (aref ,v (+ ob 5)) (* ib (- (* bx py) (* by px))))))))
       (declare (inline relative-velocity push!) (ignorable #'relative-velocity))
       ,@body))))

(defun warm-start-joints (set v d start end)
  "Apply again the carried impulse of each prepared joint of SET at rows START..END, at the start
of a substep. #J0PTDS"
  (declare (type joint-set set) (type f32-column v d) (type index start end) #.+kernel-policy+)
  (let ((rows (joint-set-rows set)))
    (with-joint-columns (kind row-a row-b rax ray raz rbx rby rbz sx sy sz ima imb iia iib
                         impulse-x impulse-y impulse-z)
        rows
      (loop for j of-type index from start below end do
        (progn
          (with-joint-row (v d j)
            (if (= (aref kind j) +joint-point+)
                (push! (aref impulse-x j) (aref impulse-y j) (aref impulse-z j))
                (let* ((cx cx) (cy cy) (cz cz)
                       (len (fsqrt (+ (* cx cx) (* cy cy) (* cz cz))))
                       (s (if (> len 1e-9) (/ (- (+ (aref impulse-x j) (aref impulse-y j)) (aref impulse-z j)) len) 0.0)))
                  (declare (type single-float cx cy cz))
                  (push! (* s cx) (* s cy) (* s cz)))))))))
  nil)
;; A point joint and a distance joint:1 ends here

;; [[file:../physics.org::#J0PTDS][A point joint and a distance joint:2]]
(defmacro solve-joint-bound (gap impulse along push)
  "Push on a distance joint's bound whose GAP (the length less the lower bound, or the upper
bound less the length) the joint closes at the speed ALONG, carrying its impulse in the column
IMPULSE: an impulse that only pushes, speculative while the bound is not reached, soft in the
solve once it is; then PUSH, a form that pushes the change Q. Expanded in solve-distance-joint.
#J0PTDS"
  `(let* ((c ,gap)
          (bias (cond ((> c 0.0) (* c inv-h)) (use-bias (* limit-bias c)) (t 0.0)))
          (ms (if (and (<= c 0.0) use-bias) limit-mass 1.0))
          (is (if (and (<= c 0.0) use-bias) (aref limit-scale j) 0.0))
          (p (- (- (* ms k (+ ,along bias))) (* is (aref ,impulse j))))
          (new (max 0.0 (+ (aref ,impulse j) p)))
          (q (- new (aref ,impulse j))))
     (setf (aref ,impulse j) new)
     ,push))

(defmacro solve-point-joint ()
  "One push of the point joint at row J: its three axes at once, through its prepared inverse
effective mass K11 .. K33, soft with the bias in the solve, rigid without it in the relax, where
it reads no separation. Expanded in solve-joints, within with-joint-row. #J0PTDS"
  `(multiple-value-bind (vx vy vz) (relative-velocity)
     (flet ((apply-point (rx ry rz ms is)
              (declare (type single-float rx ry rz ms is))
              (let ((px (- (- (* ms (+ (* (aref k11 j) rx) (* (aref k12 j) ry) (* (aref k13 j) rz))))
                           (* is (aref impulse-x j))))
                    (py (- (- (* ms (+ (* (aref k12 j) rx) (* (aref k22 j) ry) (* (aref k23 j) rz))))
                           (* is (aref impulse-y j))))
                    (pz (- (- (* ms (+ (* (aref k13 j) rx) (* (aref k23 j) ry) (* (aref k33 j) rz))))
                           (* is (aref impulse-z j)))))
                (setf (aref impulse-x j) (+ (aref impulse-x j) px)
                      (aref impulse-y j) (+ (aref impulse-y j) py)
                      (aref impulse-z j) (+ (aref impulse-z j) pz))
                (push! px py pz))))
       (declare (inline apply-point))
       (if use-bias
           (let ((br (aref bias-rate j)))
             (apply-point (+ vx (* br cx)) (+ vy (* br cy)) (+ vz (* br cz))
                          (aref mass-scale j) (aref impulse-scale j)))
           (apply-point vx vy vz 1.0 0.0)))))

(defmacro solve-distance-joint ()
  "One push of the distance joint at row J along its axis: its length (a spring in the solve
alone, a stiff length with the bias in the solve and without it in the relax), then its lower and
upper bounds (solve-joint-bound). Expanded in solve-joints, within with-joint-row. #J0PTDS"
  `(let* ((cx cx) (cy cy) (cz cz)
          (len (fsqrt (+ (* cx cx) (* cy cy) (* cz cz))))
          (s (if (> len 1e-9) (/ 1.0 len) 0.0))
          (nx (* cx s)) (ny (* cy s)) (nz (* cz s))
          (k (aref k11 j)) (f (aref flags j)))
     (declare (type single-float cx cy cz len s nx ny nz k) (type fixnum f))
     (flet ((speed-along ()
              (multiple-value-bind (vx vy vz) (relative-velocity)
                (+ (* vx nx) (* vy ny) (* vz nz)))))
       (declare (inline speed-along))
       ;; the length: a spring in the solve alone, a stiff length with the bias in the
       ;; solve and without it in the relax
       (unless (or (logtest f +joint-slack+) (and (not use-bias) (logtest f +joint-spring+)))
         (let* ((soft use-bias)
                (bias (if soft (* (aref bias-rate j) (- len (aref rest-length j))) 0.0))
                (ms (if soft (aref mass-scale j) 1.0))
                (is (if soft (aref impulse-scale j) 0.0))
                (p (- (- (* ms k (+ (speed-along) bias))) (* is (aref impulse-x j)))))
           (setf (aref impulse-x j) (+ (aref impulse-x j) p))
           (push! (* p nx) (* p ny) (* p nz))))
       ;; the bounds: impulses that only push, speculative while the bound is not reached
       (when (logtest f +joint-lower+)
         (solve-joint-bound (- len (aref min-length j)) impulse-y (speed-along)
                            (push! (* q nx) (* q ny) (* q nz))))
       (when (logtest f +joint-upper+)
         (solve-joint-bound (- (aref max-length j) len) impulse-z (- (speed-along))
                            (push! (- (* q nx)) (- (* q ny)) (- (* q nz))))))))

(defun solve-joints (set v d inv-h use-bias start end)
  "One pass over the prepared joints of SET at rows START..END: with the soft bias when USE-BIAS
(the solve), without it (the relax), but for a spring's length, which keeps its own
coefficients. #J0PTDS"
  (declare (type joint-set set) (type f32-column v d) (type single-float inv-h) (type index start end)
           #.+kernel-policy+)
  (let ((rows (joint-set-rows set))
        (limit-bias (joint-set-limit-bias set)) (limit-mass (joint-set-limit-mass set)))
    (declare (type single-float limit-bias limit-mass))
    (with-joint-columns (kind flags row-a row-b rax ray raz rbx rby rbz sx sy sz ima imb iia iib
                         k11 k12 k13 k22 k23 k33 bias-rate mass-scale impulse-scale limit-scale
                         rest-length min-length max-length impulse-x impulse-y impulse-z)
        rows
      ;; a loop for the solve and one for the relax, each compiled for its own pass
      (macrolet ((pass (biased)
                   `(let ((use-bias ,biased))
                      (loop for j of-type index from start below end do
                        (progn
                          (with-joint-row (v d j)
                            (if (= (aref kind j) +joint-point+)
                                (solve-point-joint)
                                (solve-distance-joint))))))))
        (if use-bias (pass t) (pass nil)))))
  nil)
;; A point joint and a distance joint:2 ends here

;; [[file:../physics.org::#J0BRAK][Breaking:1]]
(defun break-joints (world set)
  "Remove every solved joint of SET whose last substep impulse over the substep exceeds its break
force, each with a :joint-break event: both bodies, its first anchor's point, the force. #J0BRAK"
  (let* ((rows (joint-set-rows set))
         (inv-h (/ 1.0 (physics-world-current-h world))))
    (loop for j from (1- (joint-columns-length rows)) downto 0
          do (let ((limit (aref (joint-columns-break-force rows) j)))
               (when (and (> limit 0.0) (>= (aref (joint-columns-row-a rows) j) 0))
                 (let ((force (* inv-h (joint-row-impulse rows j))))
                   (when (> force limit)
                     (multiple-value-bind (x y z) (joint-anchor-points world j)
                       (push-event world +event-joint-break+ (aref (joint-columns-body-a rows) j)
                                   (aref (joint-columns-body-b rows) j) x y z force
                                   (aref (joint-columns-handle rows) j)))
                     (remove-joint-row world set j))))))))
;; Breaking:1 ends here

;; [[file:../physics.org::#J0SL3P][Joint groups sleep and wake together:1]]
(defun refresh-joint-groups (world set)
  "Make SET's groups current: when stale, every body slot its own group again, then one union for
each joint of two bodies. #J0SL3P"
  (ensure-joint-slots world set)
  (when (joint-set-groups-stale set)
    (let ((parent (joint-set-parent set)) (rows (joint-set-rows set)))
      (dotimes (i (length parent)) (setf (aref parent i) i))
      (dotimes (j (joint-columns-length rows))
        (let ((b (aref (joint-columns-body-b rows) j)))
          (unless (= b +no-body+)
            (setf (aref parent (group-root parent (handle-index (aref (joint-columns-body-a rows) j))))
                  (group-root parent (handle-index b))))))
      (setf (joint-set-groups-stale set) nil)))
  set)

(defmacro do-joint-bodies ((slot set) &body body)
  "Run BODY with SLOT bound to the body slot of each side of each joint of SET that is a body. #J0SL3P"
  (let ((rows (gensym "ROWS")) (j (gensym "J")) (b (gensym "B")))
    `(let ((,rows (joint-set-rows ,set)))
       (dotimes (,j (joint-columns-length ,rows))
         (let ((,slot (handle-index (aref (joint-columns-body-a ,rows) ,j)))) ,@body)
         (let ((,b (aref (joint-columns-body-b ,rows) ,j)))
           (unless (= ,b +no-body+) (let ((,slot (handle-index ,b))) ,@body)))))))

(defun wake-joint-groups (world)
  "Wake every sleeper of a joint group that has an awake body; return how many woke. Run at the
end of the wake phase. #J0SL3P"
  (let ((set (physics-world-joints world)) (woken 0))
    (when (and set (plusp (joint-columns-length (joint-set-rows set)))
               (plusp (body-columns-length (physics-world-sleeping world))))
      (refresh-joint-groups world set)
      (let* ((parent (joint-set-parent set)) (marks (joint-set-marks set))
             (ids (physics-world-ids world)) (sets (handle-table-set ids)) (locals (handle-table-local ids)))
        (do-joint-bodies (slot set) (setf (aref marks (group-root parent slot)) 0))
        (do-joint-bodies (slot set)
          (when (= (aref sets slot) +set-awake+) (setf (aref marks (group-root parent slot)) 1)))
        (do-joint-bodies (slot set)
          (when (and (= (aref sets slot) +set-sleeping+) (= 1 (aref marks (group-root parent slot))))
            (wake-physics-body world (aref locals slot))
            (incf woken)))))
    woken))

(defun sleep-joint-groups (world set)
  "Put to sleep every awake body of each joint group of SET whose awake bodies have all been
still for WORLD's time to sleep. #J0SL3P"
  (refresh-joint-groups world set)
  (let* ((parent (joint-set-parent set)) (marks (joint-set-marks set))
         (ids (physics-world-ids world)) (sets (handle-table-set ids)) (locals (handle-table-local ids))
         (stillness (body-columns-sleep-time (physics-world-awake world)))
         (time-to-sleep (f32 (physics-world-time-to-sleep world))))
    (do-joint-bodies (slot set) (setf (aref marks (group-root parent slot)) 1))
    (do-joint-bodies (slot set)
      (when (and (= (aref sets slot) +set-awake+) (< (aref stillness (aref locals slot)) time-to-sleep))
        (setf (aref marks (group-root parent slot)) 0)))
    (do-joint-bodies (slot set)
      (when (and (= (aref sets slot) +set-awake+) (= 1 (aref marks (group-root parent slot))))
        (sleep-physics-body world (aref locals slot))))))

(defun finish-joints (world)
  "The end of a step with joints, in the finalize phase: break the joints over their force, then
put to sleep the groups still for long enough, when WORLD sleeps. #J0SL3P"
  (let ((set (physics-world-joints world)))
    (when (and set (plusp (joint-columns-length (joint-set-rows set))))
      (break-joints world set)
      (when (physics-world-sleep-enabled world) (sleep-joint-groups world set)))))
;; Joint groups sleep and wake together:1 ends here

;; [[file:../physics.org::#J0OBJT][A joint as an object:1]]
(defclass physics-joint ()
  ((world :initarg :world :reader physics-joint-world)
   (handle :initarg :handle :reader physics-joint-handle))
  (:documentation "A joint as an object: a world and a joint's handle. Its numbers live in the
world's joint rows; describe shows that row as if it were slots. #J0OBJT"))

(setf (documentation 'physics-joint-world 'function) "The world of the physics-joint JOINT. #J0OBJT"
      (documentation 'physics-joint-handle 'function) "The handle of the physics-joint JOINT. #J0OBJT")

(defun physics-joint (world joint)
  "The physics-joint object for the live joint JOINT of WORLD. #J0OBJT"
  (check-world world 'physics-joint)
  (resolve-joint world joint)
  (make-instance 'physics-joint :world world :handle joint))

(defun joint-flavour (rows row)
  "What the joint at ROW of ROWS is, in words: point, or a distance joint stiff, a spring or a rope. #J0OBJT"
  (let ((flags (aref (joint-columns-flags rows) row)))
    (cond ((= (aref (joint-columns-kind rows) row) +joint-point+) "point")
          ((logtest flags +joint-slack+) "distance, a rope")
          ((logtest flags +joint-spring+) "distance, a spring")
          (t "distance, stiff"))))

(defmethod print-object ((joint physics-joint) stream)
  (print-unreadable-object (joint stream :type t)
    (let ((w (physics-joint-world joint)) (j (physics-joint-handle joint)))
      (if (physics-joint-alive-p w j)
          (let ((rows (joint-set-rows (physics-world-joints w))) (row (resolve-joint w j)))
            (multiple-value-bind (a b) (physics-joint-bodies w j)
              (format stream "~D ~A of ~D and ~:[a fixed point~;~:*~D~], ~,3F m"
                      (handle-index j) (joint-flavour rows row) (handle-index a) (and b (handle-index b))
                      (physics-joint-length w j))))
          (format stream "~D removed" (handle-index j))))))

(defun joint-summary (joint)
  "JOINT's row as (LABEL TEXT VALUE) lines: kind, bodies, anchors, length, lengths held, softness,
break force, last impulse. #J0OBJT"
  (let* ((w (physics-joint-world joint)) (j (physics-joint-handle joint))
         (rows (joint-set-rows (physics-world-joints w))) (row (resolve-joint w j)))
    (with-joint-columns (kind flags ax ay az bx by bz rest-length min-length max-length hertz damping-ratio
                         break-force)
        rows
      (multiple-value-bind (a b) (physics-joint-bodies w j)
        (let ((f (aref flags row)) (point (= (aref kind row) +joint-point+))
              (anchor-a (list (aref ax row) (aref ay row) (aref az row)))
              (anchor-b (list (aref bx row) (aref by row) (aref bz row)))
              (length (physics-joint-length w j)) (impulse (physics-joint-impulse w j)))
          (list (list "kind" (joint-flavour rows row) (if point :point :distance))
                (list "bodies" (format nil "~D and ~:[none: a fixed point~;~:*~D~]" a b) (list a b))
                (list "anchors" (format nil "~{~,4F~^ ~} in ~D's frame, ~{~,4F~^ ~} ~:[of the world~;in ~:*~D's frame~]"
                                        anchor-a a anchor-b b)
                      (list anchor-a anchor-b))
                (list "length" (format nil "~,4F m now" length) length)
                (list "holds" (if point
                                  "its anchors together"
                                  (format nil "~:[~,4F m~;~*no length of its own~]~:[~*~;, at least ~,4F m~]~:[~*~;, at most ~,4F m~]"
                                          (logtest f +joint-slack+) (aref rest-length row)
                                          (logtest f +joint-lower+) (aref min-length row)
                                          (logtest f +joint-upper+) (aref max-length row)))
                      (list (aref rest-length row) (aref min-length row) (aref max-length row)))
                (list "softness" (if (> (aref hertz row) 0.0)
                                     (format nil "~A Hz, damping ratio ~A" (aref hertz row) (aref damping-ratio row))
                                     "stiff")
                      (list (aref hertz row) (aref damping-ratio row)))
                (list "break force" (if (> (aref break-force row) 0.0) (format nil "~A N" (aref break-force row)) "none")
                      (aref break-force row))
                (list "last impulse" (format nil "~,6F N s in its last substep" impulse) impulse)))))))

(defmethod describe-object ((joint physics-joint) stream)
  (let ((w (physics-joint-world joint)) (j (physics-joint-handle joint)))
    (format stream "~&~S~%  joint handle ~D (slot ~D, generation ~D) of ~S~%" joint j (handle-index j)
            (handle-generation j) w)
    (when (physics-joint-alive-p w j)
      (loop for (label text) in (joint-summary joint)
            do (format stream "  ~18A ~A~%" label text))
      (let ((rows (joint-set-rows (physics-world-joints w))) (row (resolve-joint w j)))
        (format stream "  Its row, joint row ~D:~%" row)
        (dolist (column +joint-columns-column-names+)
          (format stream "  ~(~22A~) = ~S~%" column (aref (slot-value rows column) row)))))))

(defmethod sb-impl::inspected-parts ((joint physics-joint))
  (values (format nil "~S~%" joint) t
          (cons (cons "world" (physics-joint-world joint))
                (loop for (label nil value) in (and (physics-joint-alive-p (physics-joint-world joint)
                                                                           (physics-joint-handle joint))
                                                    (joint-summary joint))
                      collect (cons label value)))))

(defun physics-world-joint-objects (world)
  "The joints of WORLD as physics-joint objects, in the order of their rows. #J0OBJT"
  (check-world world 'physics-world-joint-objects)
  (let ((set (physics-world-joints world)))
    (and set (loop with rows = (joint-set-rows set)
                   for row below (joint-columns-length rows)
                   collect (physics-joint world (aref (joint-columns-handle rows) row))))))
;; A joint as an object:1 ends here

;; [[file:../physics.org::#BXR0WS][A box is a row and a set of extents by slot:1]]
(defconstant +box-min-half-extent+ 0.05
  "The smallest half-extent of a box body, in metres. #BXR0WS")

(define-physics-layout box-point-columns
  "The contact points of box bodies, one row a point: the solver rows of its two sides (the second
the dummy for a cell, the first the dummy for a sleeping box's corner), the point's key (its
feature), the handle of the box that found it, the normal (pushing the first side off the
second), the levers from both centres, the two tangents, the gap at the step's start, the
effective mass along the normal, the friction, the three carried impulses, then the point's
restitution, its largest push this step, the speed it struck at this step, its bounce and its normal velocity before the pass, the
twelve numbers of its angular parts along the normal, r × n and I⁻¹(r × n) for each side
([[#BXSOLV]]), and, for a point against a posted box, the box's velocity as the
first side's point velocity less the second's loses it, that velocity along the normal, and the
cap of the point's normal impulse (the largest single-float for any other point, [[#BXPUSH]]);
last its lever arm, its distance from its manifold's friction centre ([[#BXSOLV]]). #BXR0WS"
  (row fixnum) (row-b fixnum) (key fixnum) (handle fixnum)
  (sx single-float) (sy single-float) (sz single-float)
  (nx single-float) (ny single-float) (nz single-float)
  (rx single-float) (ry single-float) (rz single-float)
  (t1x single-float) (t1y single-float) (t1z single-float)
  (t2x single-float) (t2y single-float) (t2z single-float)
  (separation single-float) (normal-mass single-float) (friction single-float)
  (normal-impulse single-float) (tangent-impulse-1 single-float) (tangent-impulse-2 single-float)
  (restitution single-float) (pushed single-float) (impact-speed single-float) (bounce single-float)
  (approach single-float) (jacobian single-float 12)
  (kvx single-float) (kvy single-float) (kvz single-float) (kvn single-float) (push-cap single-float)
  (lever-arm single-float))

(define-physics-layout box-manifold-columns
  "The manifolds of the box points, one row a manifold, the points of one box against one side
along one normal ([[#BXSOLV]]): the first of its points, which lie side by side, and their count,
its friction, the friction centre's levers from both sides' centres, the mean of its points'
first levers, the inverse of its 2 x 2 tangent mass and its twist mass, its friction impulse
along the two tangents and its twist impulse about the normal, and thirty numbers: for each side
the centre's lever crossed with each tangent and the world inverse inertia times each, then each
side's world inverse inertia times the normal. #BXR0WS"
  (first fixnum) (count fixnum) (friction single-float)
  (cax single-float) (cay single-float) (caz single-float)
  (cbx single-float) (cby single-float) (cbz single-float)
  (ox single-float) (oy single-float) (oz single-float)
  (k11 single-float) (k12 single-float) (k22 single-float) (twist-mass single-float)
  (friction-impulse-1 single-float) (friction-impulse-2 single-float) (twist-impulse single-float)
  (jacobian single-float 30))

(defstruct (box-set (:constructor %make-box-set ()) (:copier nil))
  "A world's box bodies: the half-extents by handle slot (zero where a slot holds no box), how
many boxes live, the contact points of this step and of the last one, each with the first row
and the count of every slot's points, this step's manifolds of points and room for a box's
points while they are put into manifolds ([[#BXSOLV]]), the awake box rows of this step, their turns (three floats
a row), the grid of the awake boxes' centres with its rows and centres, their orientations at the
step's start (four floats a box), whether this step solves points, the soft coefficients of the
step, its restitution threshold and gravity times the substep, whether some point of the step
has restitution, the grid of the awake spheres that may meet a box with its rows, centres and
their largest travel this step, room for the rows a walk of it finds ([[#BXSPHR]]), each awake
row's inverse mass and world inverse inertia this step, eight floats a row ([[#BXSOLV]]), the
time of the substep's pass into the step, and whether some point of the step is against a
posted box ([[#BXPUSH]]). #BXR0WS"
  (hx (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (hy (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (hz (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (live 0 :type index)
  (points (make-box-point-columns) :type box-point-columns)
  (previous (make-box-point-columns) :type box-point-columns)
  (manifolds (make-box-manifold-columns) :type box-manifold-columns)
  (scratch (make-box-point-columns) :type box-point-columns)
  (first (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (count (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (previous-first (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (previous-count (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (rows (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (row-count 0 :type index)
  (turns (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (grid (make-hash-grid) :type hash-grid)
  (grid-rows (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (gx (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (gy (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (gz (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (start-q (make-array 64 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (solving nil :type boolean)
  (dummy 0 :type index)
  (bias-rate 0.0 :type single-float)
  (mass-scale 1.0 :type single-float)
  (impulse-scale 0.0 :type single-float)
  (push-max 0.0 :type single-float)
  (threshold 0.0 :type single-float)
  (bouncy nil :type boolean)
  (hgx 0.0 :type single-float) (hgy 0.0 :type single-float) (hgz 0.0 :type single-float)
  (spheres (make-hash-grid) :type hash-grid)
  (sphere-rows (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (sx (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (sy (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (sz (make-array 16 :element-type 'single-float :initial-element 0.0) :type f32-column)
  (sphere-travel 0.0 :type single-float)
  (found (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (elapsed 0.0 :type single-float) (posted nil :type boolean)
  (inertias (make-array 128 :element-type 'single-float :initial-element 0.0) :type f32-column))

(defun box-set-room (set slots)
  "Grow SET's columns by slot to hold SLOTS slots, keeping what they hold; return SET. #BXR0WS"
  (when (> slots (length (box-set-hx set)))
    (let ((n (max slots (* 2 (length (box-set-hx set))))))
      (flet ((grow-f (a) (let ((b (make-array n :element-type 'single-float :initial-element 0.0))) (replace b a) b))
             (grow-i (a) (let ((b (make-array n :element-type 'fixnum :initial-element 0))) (replace b a) b)))
        (setf (box-set-hx set) (grow-f (box-set-hx set)) (box-set-hy set) (grow-f (box-set-hy set))
              (box-set-hz set) (grow-f (box-set-hz set))
              (box-set-first set) (grow-i (box-set-first set)) (box-set-count set) (grow-i (box-set-count set))
              (box-set-previous-first set) (grow-i (box-set-previous-first set))
              (box-set-previous-count set) (grow-i (box-set-previous-count set))))))
  set)

(defun box-half-diagonal (hx hy hz)
  "The radius of the sphere that holds a box of half-extents HX HY HZ. #BXR0WS"
  (fsqrt (+ (* hx hx) (* hy hy) (* hz hz))))

(defun checked-box-extents (world hx hy hz)
  "HX HY HZ as three single-floats, once each is finite, at least +box-min-half-extent+ and at
most the largest half-extent of WORLD (max-radius-for, 2 m: four cells a side); else
invalid-physics-parameter naming :half-extents. #BXR0WS"
  (let* ((limit (max-radius-for world))
         (fx (finite-f32 :hx hx world)) (fy (finite-f32 :hy hy world)) (fz (finite-f32 :hz hz world)))
    (unless (<= +box-min-half-extent+ (min fx fy fz) (max fx fy fz) limit)
      (error 'invalid-physics-parameter :world world :name :half-extents :value (list hx hy hz)
                                        :expected (format nil "each from ~A m to ~,3F m"
                                                          +box-min-half-extent+ limit)))
    (values fx fy fz)))

(defun checked-orientation (world orientation)
  "ORIENTATION, a list of four finite reals W X Y Z not all near zero, as a unit quaternion of
four single-floats; else invalid-physics-parameter naming :orientation. #BXR0WS"
  (flet ((refuse () (error 'invalid-physics-parameter :world world :name :orientation :value orientation
                                                      :expected "a list of four finite reals W X Y Z, not all zero")))
    (unless (and (listp orientation) (= 4 (length orientation)) (every #'realp orientation)) (refuse))
    (let* ((q (mapcar (lambda (v) (finite-f32 :orientation v world)) orientation))
           (norm (fsqrt (reduce #'+ (mapcar (lambda (v) (* v v)) q)))))
      (unless (> norm 1e-3) (refuse))
      (values-list (mapcar (lambda (v) (/ v norm)) q)))))

(defun box-axes (qw qx qy qz)
  "The rotation matrix of the unit quaternion QW QX QY QZ, row by row, as nine values: its
columns are the box's axes in the world. #BXR0WS"
  (declare (type single-float qw qx qy qz))
  (let ((xx (* qx qx)) (yy (* qy qy)) (zz (* qz qz)) (xy (* qx qy)) (xz (* qx qz)) (yz (* qy qz))
        (wx (* qw qx)) (wy (* qw qy)) (wz (* qw qz)))
    (values (- 1.0 (* 2.0 (+ yy zz))) (* 2.0 (- xy wz)) (* 2.0 (+ xz wy))
            (* 2.0 (+ xy wz)) (- 1.0 (* 2.0 (+ xx zz))) (* 2.0 (- yz wx))
            (* 2.0 (- xz wy)) (* 2.0 (+ yz wx)) (- 1.0 (* 2.0 (+ xx yy))))))

(defun box-in-cells-p (world x y z hx hy hz qw qx qy qz)
  "The cell, as a list of its indices, in which the centre X Y Z or else a corner of the box of
half-extents HX HY HZ turned by QW QX QY QZ, each pulled 0.02 m towards the centre, lies when that
cell of WORLD's terrain is solid or not resident, and a second value, :centre or :corner, saying
which; NIL when none does. #BXR0WS"
  (let ((terrain (physics-world-terrain world)))
    (and terrain
         (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33) (box-axes qw qx qy qz)
           (flet ((solid (px py pz)
                    (let ((ix (cell-floor px)) (iy (cell-floor py)) (iz (cell-floor pz)))
                      (let ((chunk (gethash (chunk-key ix iy iz) (voxel-terrain-chunks terrain))))
                        (and (or (null chunk) (plusp (aref (the chunk-storage chunk) (cell-offset ix iy iz))))
                             (list ix iy iz))))))
             (let ((centre (solid x y z)))
               (if centre
                   (values centre :centre)
                   (loop for corner below 8
                         for a = (if (logbitp 0 corner) (- hx 0.02) (- 0.02 hx))
                         for b = (if (logbitp 1 corner) (- hy 0.02) (- 0.02 hy))
                         for c = (if (logbitp 2 corner) (- hz 0.02) (- 0.02 hz))
                         for cell = (solid (+ x (* r11 a) (* r12 b) (* r13 c))
                                           (+ y (* r21 a) (* r22 b) (* r23 c))
                                           (+ z (* r31 a) (* r32 b) (* r33 c)))
                         when cell return (values cell :corner)))))))))

(defun add-physics-box (world x y z hx hy hz &key mass density (orientation '(1 0 0 0)) (friction 0.6)
                                               (restitution 0.0) (vx 0.0) (vy 0.0) (vz 0.0) life
                                               (kind 0) (inside-cells :refuse) (category +default-category+)
                                               (mask +all-categories+) (gravity-scale 1.0))
  "Add an awake box centred at X Y Z with half-extents HX HY HZ, turned by ORIENTATION (a
quaternion W X Y Z, normalised), to WORLD, and return its body handle. Its mass is MASS, or
DENSITY times its volume, or 1 kg; the other keys are add-physics-body's. A box that overlaps
solid cells is refused with physics-body-in-solid-cell unless INSIDE-CELLS is :push-out; a world
made without :box-bodies refuses it with physics-feature-omitted. #BXR0WS"
  (check-idle world 'add-physics-box)
  (require-physics-feature world :box-bodies 'add-physics-box)
  (multiple-value-bind (hx hy hz) (checked-box-extents world hx hy hz)
    (multiple-value-bind (qw qx qy qz) (checked-orientation world orientation)
      (let* ((volume (* 8.0 hx hy hz))
             (m (cond ((and mass density)
                       (error 'invalid-physics-parameter :world world :name :density :value density
                                                         :expected "NIL when a mass is given"))
                      (mass mass)
                      (density (* volume (finite-f32 :density density world)))
                      (t 1.0)))
             (fx (finite-f32 :x x world)) (fy (finite-f32 :y y world)) (fz (finite-f32 :z z world)))
        (check-coordinate :x fx world) (check-coordinate :y fy world) (check-coordinate :z fz world)
        (unless (member inside-cells '(:refuse :push-out))
          (error 'invalid-physics-parameter :world world :name :inside-cells :value inside-cells
                                            :expected ":refuse or :push-out"))
        (multiple-value-bind (cell part) (and (eq inside-cells :refuse) (box-in-cells-p world fx fy fz hx hy hz qw qx qy qz))
          (when cell
            (error 'physics-body-in-solid-cell :world world :operation 'add-physics-box :name :position
                                               :value (list x y z) :cell cell
                                               :part (if (eq part :centre) "the centre" "a corner of the box centred at")
                                               :resident (apply #'terrain-resident-p (physics-world-terrain world) cell)
                                               :expected "a box clear of solid and non-resident cells")))
        (check-body-room world 'add-physics-box)
        ;; add-physics-body checks the rest before it touches the world
        (let* ((handle (let ((*box-radius-limit* (let ((e (max-radius-for world))) (box-half-diagonal e e e))))
                         (add-physics-body world fx fy fz :radius (box-half-diagonal hx hy hz) :mass m
                                           :friction friction :restitution restitution :vx vx :vy vy :vz vz :life life
                                           :collide-with-bodies nil :kind kind :inside-cells :push-out
                                           :category category :mask mask :gravity-scale gravity-scale)))
               (set (or (physics-world-box-bodies world)
                        (setf (physics-world-box-bodies world) (%make-box-set))))
               (slot (handle-index handle))
               (row (nth-value 1 (resolve-handle world handle)))
               (m (f32 m)))
          (box-set-room set (handle-table-count (physics-world-ids world)))
          (setf (aref (box-set-hx set) slot) hx (aref (box-set-hy set) slot) hy (aref (box-set-hz set) slot) hz)
          (incf (box-set-live set))
          (with-body-columns ((bqw qw) (bqx qx) (bqy qy) (bqz qz) inverse-inertia flags) (physics-world-awake world)
            (setf (aref bqw row) qw (aref bqx row) qx (aref bqy row) qy (aref bqz row) qz
                  (aref inverse-inertia row) (/ 9.0 (* 2.0 m (+ (* hx hx) (* hy hy) (* hz hz))))
                  (aref flags row) (logior (aref flags row) +flag-box-shape+)))
          handle)))))

(defun physics-body-box-p (world handle)
  "True when HANDLE's live body is a box. #BXR0WS"
  (check-world world 'physics-body-box-p)
  (multiple-value-bind (set row) (resolve-handle world handle)
    (logtest (aref (body-columns-flags (set-buffer world set)) row) +flag-box-shape+)))

(defun physics-box-half-extents (world handle)
  "The half-extents of HANDLE's box body as three values; zeros for a sphere. #BXR0WS"
  (check-world world 'physics-box-half-extents)
  (resolve-handle world handle)
  (let ((set (physics-world-box-bodies world)) (slot (handle-index handle)))
    (if (and set (physics-body-box-p world handle))
        (values (aref (box-set-hx set) slot) (aref (box-set-hy set) slot) (aref (box-set-hz set) slot))
        (values 0.0 0.0 0.0))))

(defun forget-box (world handle)
  "Zero the extents of HANDLE's slot in WORLD's box set, its body about to be removed, when that
body is a box. #BXR0WS"
  (let ((set (physics-world-box-bodies world)) (slot (handle-index handle)))
    (when (and set (< slot (length (box-set-hx set))) (plusp (aref (box-set-hx set) slot)))
      (setf (aref (box-set-hx set) slot) 0.0 (aref (box-set-hy set) slot) 0.0 (aref (box-set-hz set) slot) 0.0
            (aref (box-set-count set) slot) 0 (aref (box-set-previous-count set) slot) 0)
      (decf (box-set-live set)))))

(defun validate-box-set (world fail)
  "Check WORLD's box set against its rows, calling FAIL with a format control and arguments at the
first break: a slot holds extents exactly when its body has the box flag, every extent within its
bounds, and the count of live boxes is theirs. #BXR0WS"
  (let ((set (physics-world-box-bodies world)) (boxes 0))
    (when set
      (dolist (buffer (list (physics-world-awake world) (physics-world-sleeping world)))
        (dotimes (row (body-columns-length buffer))
          (let* ((h (aref (body-columns-handle buffer) row)) (slot (handle-index h))
                 (box (logtest (aref (body-columns-flags buffer) row) +flag-box-shape+))
                 (hx (if (< slot (length (box-set-hx set))) (aref (box-set-hx set) slot) 0.0)))
            (when box (incf boxes))
            (unless (eq box (plusp hx))
              (funcall fail "handle ~D: box flag ~A but extent ~A" h box hx))
            (when (and box (< (aref (box-set-hx set) slot) +box-min-half-extent+))
              (funcall fail "handle ~D: extent below ~A" h +box-min-half-extent+)))))
      (unless (= boxes (box-set-live set))
        (funcall fail "~D box rows but the box set counts ~D" boxes (box-set-live set))))))
;; A box is a row and a set of extents by slot:1 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:1]]
(defconstant +box-point-lattice-bit+ 33
  "The bit of a box point's key that marks a lattice point of the cells, not a corner of the box. #BXCELL")

(declaim (inline box-corner-key box-lattice-key))
(defun box-corner-key (slot corner face)
  "The key of corner CORNER (0-7) of the box in handle slot SLOT against a cell face of direction
FACE (0-5: -x +x -y +y -z +z). #BXCELL"
  (declare (type (unsigned-byte 24) slot) (type (integer 0 7) corner) (type (integer 0 5) face))
  (logior (ash slot 34) (+ (* corner 6) face)))

(defun box-lattice-key (slot x y z face)
  "The key of the lattice point X Y Z against face FACE (0-5) of the box in handle slot SLOT. #BXCELL"
  (declare (type (unsigned-byte 24) slot) (type fixnum x y z) (type (integer 0 5) face))
  (logior (ash slot 34) (ash 1 +box-point-lattice-bit+)
          (ash (ldb (byte 10 0) x) 23) (ash (ldb (byte 10 0) y) 13) (ash (ldb (byte 10 0) z) 3) face))

(declaim (inline box-edge-key))
(defun box-edge-key (slot x y z axis edge)
  "The key of the cell edge from the lattice point X Y Z along AXIS (0-2: x y z) against edge EDGE
(0-11) of the box in handle slot SLOT: the lattice bit, the point modulo 2^8 on each axis, and 7
in the three low bits, where a lattice point's key has its face. #BXCELL"
  (declare (type (unsigned-byte 24) slot) (type fixnum x y z) (type (integer 0 2) axis) (type (integer 0 11) edge))
  (logior (ash slot 34) (ash 1 +box-point-lattice-bit+)
          (ash (ldb (byte 8 0) x) 25) (ash (ldb (byte 8 0) y) 17) (ash (ldb (byte 8 0) z) 9)
          (ash (+ (* 12 axis) edge) 3) 7))

(defun add-box-point (set row handle key nx ny nz rx ry rz gap &optional (row-b (box-set-dummy set))
                                                                          (sx 0.0) (sy 0.0) (sz 0.0))
  "Append to SET's points the point KEY found by the box HANDLE, between the sides at solver rows
ROW and ROW-B (the dummy by default: a cell): normal NX NY NZ pushing the first side, levers RX RY
RZ and SX SY SZ from the two centres, gap GAP; its impulses are those its key had last step, or
zeros. #BXCELL"
  (declare (type box-set set) (type index row row-b) (type fixnum handle key)
           (type single-float nx ny nz rx ry rz gap sx sy sz) #.+kernel-policy+)
  (let* ((points (box-set-points set))
         (k (box-point-columns-append points))
         (old (box-set-previous set))
         (slot (handle-index handle))
         (from (aref (box-set-previous-first set) slot))
         (to (min (box-point-columns-length old) (+ from (aref (box-set-previous-count set) slot)))))
    (declare (type index k from) (type fixnum to))
    (with-box-point-columns ((r row) (rb row-b) (kc key) (hc handle) (cnx nx) (cny ny) (cnz nz)
                             (crx rx) (cry ry) (crz rz) (csx sx) (csy sy) (csz sz)
                             separation normal-impulse tangent-impulse-1 tangent-impulse-2
                             kvx kvy kvz kvn push-cap)
        points
      ;; still cells and bodies: no kinematic velocity, no cap ([[#BXPUSH]])
      (setf (aref kvx k) 0.0 (aref kvy k) 0.0 (aref kvz k) 0.0 (aref kvn k) 0.0
            (aref push-cap k) most-positive-single-float)
      (setf (aref r k) row (aref rb k) row-b (aref kc k) key (aref hc k) handle
            (aref cnx k) nx (aref cny k) ny (aref cnz k) nz (aref crx k) rx (aref cry k) ry (aref crz k) rz
            (aref csx k) sx (aref csy k) sy (aref csz k) sz
            (aref separation k) gap)
      (with-box-point-columns ((okey key) (on normal-impulse) (o1 tangent-impulse-1) (o2 tangent-impulse-2)) old
        (loop for j of-type fixnum from from below to
              when (= (aref okey j) key)
                do (setf (aref normal-impulse k) (aref on j) (aref tangent-impulse-1 k) (aref o1 j)
                         (aref tangent-impulse-2 k) (aref o2 j))
                   (return))))
    k))
;; A box against the cells:1 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:2]]
(defmacro each-cell-face (form)
  "FORM once for each of a cell's six faces, with FACE (0 to 5: -x +x -y +y -z +z), the distance
D to it (the variables D0 to D5), the offset OX OY OZ of the neighbour across it and the normal NX
NY NZ out of that neighbour bound as symbol macros. #BXCELL"
  `(progn
     ,@(loop for (face dist ox oy oz nx ny nz)
               in '((0 d0 -1 0 0 1.0 0.0 0.0) (1 d1 1 0 0 -1.0 0.0 0.0)
                    (2 d2 0 -1 0 0.0 1.0 0.0) (3 d3 0 1 0 0.0 -1.0 0.0)
                    (4 d4 0 0 -1 0.0 0.0 1.0) (5 d5 0 0 1 0.0 0.0 -1.0))
             collect `(symbol-macrolet ((face ,face) (d ,dist) (ox ,ox) (oy ,oy) (oz ,oz)
                                        (nx ,nx) (ny ,ny) (nz ,nz))
                        ,form))))

(defmacro box-corner-points ()
  "Add the points of the box's eight corners against the faces of the cells: a corner inside a
solid cell is pushed out through its nearest face whose neighbour is air, a corner in the air
meets each solid neighbour across a face nearer than the reach. Expanded in find-box-points,
whose variables it reads. #BXCELL"
  `(dotimes (corner 8)
     (let* ((a (if (logbitp 0 corner) hx (- hx))) (b (if (logbitp 1 corner) hy (- hy)))
            (c (if (logbitp 2 corner) hz (- hz)))
            (rx (+ (* r11 a) (* r12 b) (* r13 c))) (ry (+ (* r21 a) (* r22 b) (* r23 c)))
            (rz (+ (* r31 a) (* r32 b) (* r33 c)))
            (px (+ cx rx)) (py (+ cy ry)) (pz (+ cz rz))
            (ix (cell-floor px)) (iy (cell-floor py)) (iz (cell-floor pz))
            ;; the distances to the cell's six faces: -x +x -y +y -z +z
            (d0 (- px (float ix 1.0))) (d1 (- (float (1+ ix) 1.0) px))
            (d2 (- py (float iy 1.0))) (d3 (- (float (1+ iy) 1.0) py))
            (d4 (- pz (float iz 1.0))) (d5 (- (float (1+ iz) 1.0) pz)))
       (declare (type single-float a b c rx ry rz px py pz d0 d1 d2 d3 d4 d5) (type fixnum ix iy iz))
       (if (solid ix iy iz)
           ;; inside a solid cell: the nearest face whose neighbour is air, out of it
           (let ((best -1) (depth most-positive-single-float) (bnx 0.0) (bny 0.0) (bnz 0.0))
             (declare (type fixnum best) (type single-float depth bnx bny bnz))
             (each-cell-face (when (and (< d depth) (not (solid (+ ix ox) (+ iy oy) (+ iz oz)))
                                   (> (+ (* nx rx) (* ny ry) (* nz rz)) 0.0))
                          (setf best face depth d bnx (- nx) bny (- ny) bnz (- nz))))
             (when (>= best 0)
               (add-box-point set row h (box-corner-key slot corner best) bnx bny bnz rx ry rz (- depth))))
           ;; in air: each solid neighbour across a face nearer than the reach
           (each-cell-face (when (and (< d reach) (solid (+ ix ox) (+ iy oy) (+ iz oz))
                                 (< (+ (* nx rx) (* ny ry) (* nz rz)) 0.0))
                        (add-box-point set row h (box-corner-key slot corner face) nx ny nz rx ry rz d)))))))
;; A box against the cells:2 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:3]]
(defmacro box-lattice-point ()
  "Add the point of the lattice point LX LY LZ, where SOLIDS of its eight cells meet (one to
three: a convex corner of the cells) whose centres lie, summed, GX GY GZ from it: against the
box's face it is least inside of, or farthest out of, among those whose push takes the box away
from the solid cells. Expanded in find-box-points, whose variables it reads. #BXCELL"
  `(when (<= 1 solids 3)
     (let* ((rx (- (float lx 1.0) cx)) (ry (- (float ly 1.0) cy)) (rz (- (float lz 1.0) cz))
            ;; the point in the box's frame, and how far out of each face pair
            (u (+ (* r11 rx) (* r21 ry) (* r31 rz)))
            (v (+ (* r12 rx) (* r22 ry) (* r32 rz)))
            (w (+ (* r13 rx) (* r23 ry) (* r33 rz)))
            (ou (- (abs u) hx)) (ov (- (abs v) hy)) (ow (- (abs w) hz)))
       (declare (type single-float rx ry rz u v w ou ov ow))
       (when (and (< ou reach) (< ov reach) (< ow reach))
         ;; the face it is least inside of, or farthest out of, among those
         ;; whose push takes the box away from the solid cells: a face whose
         ;; outward normal points into them, as G does (the solid cells'
         ;; centres less the point)
         (let ((best -1) (gap most-negative-single-float)
               (ga (+ (* r11 gx) (* r21 gy) (* r31 gz)))
               (gb (+ (* r12 gx) (* r22 gy) (* r32 gz)))
               (gc (+ (* r13 gx) (* r23 gy) (* r33 gz)))
               (glimit (* 0.25 (fsqrt (+ (* gx gx) (* gy gy) (* gz gz))))))
           (declare (type fixnum best) (type single-float gap ga gb gc glimit))
           (macrolet ((face (index out along sign)
                        ;; within 75 degrees of the way to the solid cells
                        `(when (and (> (* ,sign ,along) glimit) (> ,out gap))
                           (setf best ,index gap ,out))))
             (face 0 (- (- u) hx) ga -1.0) (face 1 (- u hx) ga 1.0)
             (face 2 (- (- v) hy) gb -1.0) (face 3 (- v hy) gb 1.0)
             (face 4 (- (- w) hz) gc -1.0) (face 5 (- w hz) gc 1.0))
           (when (>= best 0)
             ;; the push is the face's inward normal
             (multiple-value-bind (nx ny nz)
                 (case best
                   (0 (values r11 r21 r31)) (1 (values (- r11) (- r21) (- r31)))
                   (2 (values r12 r22 r32)) (3 (values (- r12) (- r22) (- r32)))
                   (4 (values r13 r23 r33)) (t (values (- r13) (- r23) (- r33))))
               (declare (type single-float nx ny nz))
               (add-box-point set row h (box-lattice-key slot lx ly lz best)
                              nx ny nz rx ry rz gap))))))))

(defconstant +box-edge-cone+ 0.6427876
  "The cosine of the widest angle, 50 degrees, between the push a convex edge of the cells gives a
box's edge and the way out of its solid cell: the edge's own cone of normals is 45 degrees
either side of that way, between its two faces' normals. #BXCELL")

(defun box-cell-edge-point (set row h qx qy qz axis gx gy gz cone cx cy cz axes halves j reach)
  "Add the point where the box at solver ROW (handle H, centre CX CY CZ, half-extents HALVES, its
axes the columns of AXES, row by row) crosses, with its edge along its axis J nearest the cells,
the convex edge of the cells from the lattice point QX QY QZ along AXIS, whose one solid cell lies
GX GY GZ from the edge: when the edges' common perpendicular, turned out of the solid cell, lies
within CONE of that way (the cone's cosine times the length of G), their nearest points lie within
both edges, and the gap along it is under REACH and above the box's least half-extent less. #BXCELL"
  (declare (type box-set set) (type index row) (type fixnum h qx qy qz) (type (integer 0 2) axis j)
           (type single-float gx gy gz cone cx cy cz reach)
           (type (simple-array single-float (9)) axes) (type (simple-array single-float (3)) halves)
           #.+kernel-policy+)
  (let* ((k (mod (+ j 1) 3)) (l (mod (+ j 2) 3))
         (ux (aref axes j)) (uy (aref axes (+ 3 j))) (uz (aref axes (+ 6 j)))
         (ua (case axis (0 ux) (1 uy) (t uz))) (denom (- 1.0 (* ua ua))))
    (declare (type (integer 0 2) k l) (type single-float ux uy uz ua denom))
    ;; edges within a milliradian of parallel name no direction
    (when (> denom 1e-6)
      (let* ((norm (/ 1.0 (fsqrt denom)))
             ;; the common perpendicular, the cell edge's axis crossed with the box's
             (mx (* norm (case axis (0 0.0) (1 uz) (t (- uy)))))
             (my (* norm (case axis (0 (- uz)) (1 0.0) (t ux))))
             (mz (* norm (case axis (0 uy) (1 (- ux)) (t 0.0))))
             ;; turned out of the solid cell
             (out (if (> (+ (* mx gx) (* my gy) (* mz gz)) 0.0) -1.0 1.0))
             (nx (* out mx)) (ny (* out my)) (nz (* out mz))
             ;; the box's edge along J that lies farthest against the push, the support of -N
             (hk (if (> (+ (* nx (aref axes k)) (* ny (aref axes (+ 3 k))) (* nz (aref axes (+ 6 k)))) 0.0)
                     (- (aref halves k)) (aref halves k)))
             (hl (if (> (+ (* nx (aref axes l)) (* ny (aref axes (+ 3 l))) (* nz (aref axes (+ 6 l)))) 0.0)
                     (- (aref halves l)) (aref halves l)))
             (px (+ cx (* hk (aref axes k)) (* hl (aref axes l))))
             (py (+ cy (* hk (aref axes (+ 3 k))) (* hl (aref axes (+ 3 l)))))
             (pz (+ cz (* hk (aref axes (+ 6 k))) (* hl (aref axes (+ 6 l)))))
             (ex (float qx 1.0)) (ey (float qy 1.0)) (ez (float qz 1.0))
             (rx (- ex px)) (ry (- ey py)) (rz (- ez pz))
             (gap (- (+ (* nx rx) (* ny ry) (* nz rz))))
             ;; the nearest points: TT along the cell edge, SS along the box's
             (f (+ (* ux rx) (* uy ry) (* uz rz)))
             (tt (/ (- (* ua f) (case axis (0 rx) (1 ry) (t rz))) denom))
             (ss (+ f (* tt ua))))
        (declare (type single-float norm mx my mz out nx ny nz hk hl px py pz ex ey ez rx ry rz gap f tt ss))
        (when (and (>= (- (+ (* nx gx) (* ny gy) (* nz gz))) cone)
                   (< gap reach) (> gap (- (min (aref halves 0) (aref halves 1) (aref halves 2))))
                   (< 0.0 tt 1.0) (< (abs ss) (aref halves j)))
          ;; the point midway between the nearest points
          (add-box-point set row h
                         (box-edge-key (handle-index h) qx qy qz axis (+ (* 4 j) (if (> hk 0.0) 1 0) (if (> hl 0.0) 2 0)))
                         nx ny nz
                         (- (* 0.5 (+ ex (if (= axis 0) tt 0.0) px (* ss ux))) cx)
                         (- (* 0.5 (+ ey (if (= axis 1) tt 0.0) py (* ss uy))) cy)
                         (- (* 0.5 (+ ez (if (= axis 2) tt 0.0) pz (* ss uz))) cz)
                         gap))))))

(defun box-cell-edge-points (set row h qx qy qz axis gx gy gz cx cy cz hx hy hz
                             r11 r12 r13 r21 r22 r23 r31 r32 r33 reach)
  "Add the points where the box at solver ROW (handle H, centre CX CY CZ, half-extents HX HY HZ,
axes the columns of R) crosses the convex edge of the cells from the lattice point QX QY QZ along
AXIS, whose one solid cell lies GX GY GZ from the edge: one for each of the box's three axes whose
edge nearest the cells meets it (box-cell-edge-point), within +box-edge-cone+. #BXCELL"
  (declare (type single-float gx gy gz hx hy hz r11 r12 r13 r21 r22 r23 r31 r32 r33) #.+kernel-policy+)
  (let ((axes (make-array 9 :element-type 'single-float))
        (halves (make-array 3 :element-type 'single-float))
        (cone (* +box-edge-cone+ (fsqrt (+ (* gx gx) (* gy gy) (* gz gz))))))
    (declare (dynamic-extent axes halves))
    (setf (aref axes 0) r11 (aref axes 1) r12 (aref axes 2) r13 (aref axes 3) r21 (aref axes 4) r22
          (aref axes 5) r23 (aref axes 6) r31 (aref axes 7) r32 (aref axes 8) r33
          (aref halves 0) hx (aref halves 1) hy (aref halves 2) hz)
    (dotimes (j 3)
      (box-cell-edge-point set row h qx qy qz axis gx gy gz cone cx cy cz axes halves j reach))))

(defmacro with-box-lattice-range (&body body)
  "Run BODY with X0 Y0 Z0 and X1 Y1 Z1 bound to the lowest and highest lattice points within the
reach of the box's bounding box on each axis (a range no point falls in takes the one below),
for box-near-cells-p and box-lattice-points to share. Expanded in find-box-points, whose variables
it reads. #BXCELL"
  `(let* ((ex (+ (* (abs r11) hx) (* (abs r12) hy) (* (abs r13) hz) reach))
          (ey (+ (* (abs r21) hx) (* (abs r22) hy) (* (abs r23) hz) reach))
          (ez (+ (* (abs r31) hx) (* (abs r32) hy) (* (abs r33) hz) reach))
          (x1 (cell-floor (+ cx ex))) (y1 (cell-floor (+ cy ey))) (z1 (cell-floor (+ cz ez)))
          (x0 (min x1 (1+ (cell-floor (- cx ex))))) (y0 (min y1 (1+ (cell-floor (- cy ey)))))
          (z0 (min z1 (1+ (cell-floor (- cz ez))))))
     (declare (type single-float ex ey ez) (type fixnum x0 y0 z0 x1 y1 z1))
     ,@body))

(defmacro box-lattice-points ()
  "Add the points of the convex lattice points of the cells from X0 Y0 Z0 to X1 Y1 Z1
(with-box-lattice-range) against the box's faces (box-lattice-point), and of the convex edges of
the cells from them against the box's edges (box-cell-edge-points): each edge from a point up its
axis, and from the lowest points of the range down it too, so every edge that meets the range is
taken once. Expanded in find-box-points, whose variables it reads. #BXCELL"
  `(loop for lx of-type fixnum from x0 to x1 do
       (loop for ly of-type fixnum from y0 to y1 do
         (loop for lz of-type fixnum from z0 to z1 do
           (let ((solids 0) (bits 0) (gx 0.0) (gy 0.0) (gz 0.0))
             (declare (type fixnum solids) (type (unsigned-byte 8) bits) (type single-float gx gy gz))
             ;; how many of the eight cells are solid, which, and where they lie from the point
             (dotimes (k 8)
               (when (solid (- lx (if (logbitp 0 k) 0 1)) (- ly (if (logbitp 1 k) 0 1))
                            (- lz (if (logbitp 2 k) 0 1)))
                 (incf solids)
                 (setf bits (logior bits (ash 1 k))
                       gx (+ gx (if (logbitp 0 k) 0.5 -0.5)) gy (+ gy (if (logbitp 1 k) 0.5 -0.5))
                       gz (+ gz (if (logbitp 2 k) 0.5 -0.5)))))
             (box-lattice-point)
             ;; a convex edge has one solid cell of its four, so its end has one to five of eight
             (when (<= 1 solids 5)
               (box-cell-edges bits lx ly lz x0 y0 z0)))))))

(defmacro box-cell-edges (bits lx ly lz x0 y0 z0)
  "Test the convex edges of the cells at the lattice point LX LY LZ, whose eight cells' solid ones
BITS marks (bit K the cell below the point on each axis whose bit of K is clear), against the
box's edges: along each axis, the edge up from the point, whose four cells are those of the
point's eight on the axis's upper side, and, at the range's lowest point X0 Y0 Z0 on that axis,
the edge down to it. Expanded in box-lattice-points. #BXCELL"
  `(macrolet ((edge (axis mask qx qy qz)
                ;; the edge's four cells are BITS under MASK; with one solid, its centre lies half a
                ;; cell across each of the other two axes
                `(let ((cells (logand ,',bits ,mask)))
                   (when (= 1 (logcount cells))
                     (let ((k (integer-length (1- cells))))
                       (box-cell-edge-points set row h ,qx ,qy ,qz ,axis
                                             (if (= ,axis 0) 0.0 (if (logbitp 0 k) 0.5 -0.5))
                                             (if (= ,axis 1) 0.0 (if (logbitp 1 k) 0.5 -0.5))
                                             (if (= ,axis 2) 0.0 (if (logbitp 2 k) 0.5 -0.5))
                                             cx cy cz hx hy hz r11 r12 r13 r21 r22 r23 r31 r32 r33 reach))))))
     (edge 0 #xAA ,lx ,ly ,lz) (edge 1 #xCC ,lx ,ly ,lz) (edge 2 #xF0 ,lx ,ly ,lz)
     (when (= ,lx ,x0) (edge 0 #x55 (1- ,lx) ,ly ,lz))
     (when (= ,ly ,y0) (edge 1 #x33 ,lx (1- ,ly) ,lz))
     (when (= ,lz ,z0) (edge 2 #x0F ,lx ,ly (1- ,lz)))))
;; A box against the cells:3 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:4]]
(defmacro box-near-cells-p ()
  "True when some cell the scan of box-lattice-points reads is solid: the cells on either side of
each lattice point from X0 Y0 Z0 to X1 Y1 Z1 (with-box-lattice-range). Expanded in
find-box-points, whose variables it reads. #BXCELL"
  `(loop for ix of-type fixnum from (1- x0) to x1
         thereis (loop for iy of-type fixnum from (1- y0) to y1
                       thereis (loop for iz of-type fixnum from (1- z0) to z1
                                     thereis (solid ix iy iz)))))

(defun find-box-points (world set row reach)
  "Append to SET's points every point of the box at awake ROW of WORLD against the cells within
REACH of its surface: its corners against cell faces, the convex lattice points of the cells
against its faces. #BXCELL"
  (declare (type box-set set) (type index row) (type single-float reach) #.+kernel-policy+)
  (let ((terrain (physics-world-terrain world))
        (probe (physics-world-probe world)))
    (when terrain
      (with-body-columns (x y z qw qx qy qz handle) (physics-world-awake world)
        (let* ((h (aref handle row)) (slot (handle-index h))
               (cx (aref x row)) (cy (aref y row)) (cz (aref z row))
               (hx (aref (box-set-hx set) slot)) (hy (aref (box-set-hy set) slot)) (hz (aref (box-set-hz set) slot)))
          (declare (type single-float cx cy cz hx hy hz))
          (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33)
              (box-axes (aref qw row) (aref qx row) (aref qy row) (aref qz row))
            (declare (type single-float r11 r12 r13 r21 r22 r23 r31 r32 r33))
            (flet ((solid (ix iy iz)
                     (declare (type fixnum ix iy iz))
                     (probe-solid-p probe ix iy iz)))
              (declare (inline solid))
              (with-box-lattice-range
                ;; nothing to meet unless a cell the lattice points' scan reads is solid
                (when (box-near-cells-p)
                  ;; the corners against the faces of the cells
                  (box-corner-points)
                  ;; the convex lattice points of the cells against the faces of the box
                  (box-lattice-points)))))))))
  set)
;; A box against the cells:4 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:7]]
(defconstant +box-axis-tolerance+ 5e-4
  "How much farther apart the second box's face must hold two boxes than the first's best for
it to be the reference, in metres: a tenth of the slop, as Box2D's polygons do. #BXCELL")

(defconstant +box-clip-tolerance+ 1e-3
  "How far past a side of the reference face an incident corner may lie and still be kept as
it is, in metres. #BXCELL")

(defun reduce-box-manifold (poly keep kept)
  "Choose four of the KEPT vertices whose places in POLY (three floats a vertex: two coordinates
in the reference face and the gap) the first KEPT entries of KEEP hold: the deepest, the one
farthest from it, and the two that span the largest areas with those on either side of the line
through them; write their places into KEEP in increasing order and return 4. #BXCELL"
  (declare (type (simple-array single-float (24)) poly) (type (simple-array fixnum (8)) keep)
           (type (integer 5 8) kept) #.+kernel-policy+)
  (macrolet ((a (q) `(aref poly (* 3 (the (integer 0 7) (aref keep ,q)))))
             (b (q) `(aref poly (+ 1 (* 3 (the (integer 0 7) (aref keep ,q))))))
             (gap (q) `(aref poly (+ 2 (* 3 (the (integer 0 7) (aref keep ,q)))))))
    (let ((p1 0) (p2 0) (p3 0) (p4 0))
      (declare (type (integer 0 7) p1 p2 p3 p4))
      (loop for q from 1 below kept when (< (gap q) (gap p1)) do (setf p1 q))
      (let ((far -1.0))
        (declare (type single-float far))
        (dotimes (q kept)
          (let ((d (+ (expt (- (a q) (a p1)) 2) (expt (- (b q) (b p1)) 2))))
            (when (and (/= q p1) (> d far)) (setf p2 q far d)))))
      ;; twice the signed area of the triangle P1 P2 Q, most positive and most negative
      (let ((most most-negative-single-float) (least most-positive-single-float))
        (declare (type single-float most least))
        (dotimes (q kept)
          (unless (or (= q p1) (= q p2))
            (let ((area (- (* (- (a p2) (a p1)) (- (b q) (b p1))) (* (- (b p2) (b p1)) (- (a q) (a p1))))))
              (when (> area most) (setf p3 q most area)))))
        (dotimes (q kept)
          (unless (or (= q p1) (= q p2) (= q p3))
            (let ((area (- (* (- (a p2) (a p1)) (- (b q) (b p1))) (* (- (b p2) (b p1)) (- (a q) (a p1))))))
              (when (< area least) (setf p4 q least area))))))
      ;; the four places, in increasing order
      (let ((c1 (aref keep p1)) (c2 (aref keep p2)) (c3 (aref keep p3)) (c4 (aref keep p4)))
        (declare (type fixnum c1 c2 c3 c4))
        (setf (aref keep 0) c1 (aref keep 1) c2 (aref keep 2) c3 (aref keep 3) c4)
        (loop for q from 1 below 4
              do (let ((v (aref keep q)) (r q))
                   (declare (type fixnum v r))
                   (loop while (and (> r 0) (> (aref keep (1- r)) v))
                         do (setf (aref keep r) (aref keep (1- r)))
                            (decf r))
                   (setf (aref keep r) v))))
      4)))

(defmacro nth-of (k c1 c2 c3)
  "C1, C2 or C3, as K is 0, 1 or 2. #BXCELL"
  `(case ,k (0 ,c1) (1 ,c2) (t ,c3)))
;; A box against the cells:7 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:8]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun box-axis-name (control &rest numbers)
    "The symbol CONTROL formats NUMBERS to, in this package: A12 (A's axes row 1 column 2), C01
(A's axis 0 with B's axis 1), AC01 (its magnitude), TA0 (the offset along A's axis 0). #BXCELL"
    (intern (apply #'format nil control numbers) (find-package :luv-physics))))

(defmacro box-face-axis (index along own-half other-halves magnitudes)
  "Set BEST and BEST-SEP to INDEX and the distance along the face axis INDEX when farther than
BEST-SEP: the offset ALONG it less the axis's own box's half-extent OWN-HALF less the other's
OTHER-HALVES times its axes' MAGNITUDES along it. Expanded in box-separating-axes. #BXCELL"
  `(let ((sep (- (abs ,along) ,own-half (+ ,@(mapcar (lambda (h c) `(* ,h ,c)) other-halves magnitudes)))))
     (declare (type single-float sep))
     (when (> sep best-sep) (setf best ,index best-sep sep))))

(defmacro box-edge-axis (i j)
  "Leave the test with no axis when the edge axis of A's axis I crossed with B's axis J holds the
boxes REACH apart, else set EDGE, EDGE-SEP and ELX ELY ELZ to it when farther than EDGE-SEP; but
for edges near parallel. Expanded in box-separating-axes. #BXCELL"
  (flet ((c (p q) (box-axis-name "C~D~D" p q)) (ac (p q) (box-axis-name "AC~D~D" p q))
         (ta (k) (box-axis-name "TA~D" k)) (ah (k) (nth k '(ahx ahy ahz))) (bh (k) (nth k '(bhx bhy bhz)))
         (a (m) (box-axis-name "A~D~D" (1+ m) (1+ i))) (b (m) (box-axis-name "B~D~D" (1+ m) (1+ j))))
    (let ((i1 (mod (+ i 1) 3)) (i2 (mod (+ i 2) 3)) (j1 (mod (+ j 1) 3)) (j2 (mod (+ j 2) 3)))
      `(let ((len2 (+ (* ,(c i1 j) ,(c i1 j)) (* ,(c i2 j) ,(c i2 j)))))
         (declare (type single-float len2))
         (when (> len2 1e-6)
           (let* ((f (/ 1.0 (fsqrt len2)))
                  (sep (* f (- (abs (- (* ,(ta i2) ,(c i1 j)) (* ,(ta i1) ,(c i2 j))))
                               (+ (* ,(ah i1) ,(ac i2 j)) (* ,(ah i2) ,(ac i1 j)))
                               (+ (* ,(bh j1) ,(ac i j2)) (* ,(bh j2) ,(ac i j1)))))))
             (declare (type single-float f sep))
             (when (>= sep reach) (return-from test nil))
             (when (> sep edge-sep)
               ;; the axis's direction in the world, A_i x B_j over its length
               (setf edge ,(+ (* 3 i) j) edge-sep sep
                     elx (* f (- (* ,(a 1) ,(b 2)) (* ,(a 2) ,(b 1))))
                     ely (* f (- (* ,(a 2) ,(b 0)) (* ,(a 0) ,(b 2))))
                     elz (* f (- (* ,(a 0) ,(b 1)) (* ,(a 1) ,(b 0))))))))))))

(defmacro box-separating-axes ()
  "The body of box-separating-axis: the products C = A^T B and their magnitudes, the offset in
A's frame and in B's, then the six face axes and the nine edge axes read from them, leaving with
BEST -1 as soon as an axis holds the boxes REACH apart. #BXCELL"
  (flet ((c (i j) (box-axis-name "C~D~D" i j)) (ac (i j) (box-axis-name "AC~D~D" i j))
         (column (box k) (loop for m from 1 to 3 collect (box-axis-name "~A~D~D" box m (1+ k))))
         (dot (u v) `(+ ,@(mapcar (lambda (p q) `(* ,p ,q)) u v))))
    (let ((pairs (loop for i below 3 append (loop for j below 3 collect (list i j)))))
      `(let* (,@(loop for (i j) in pairs collect `(,(c i j) ,(dot (column "A" i) (column "B" j))))
              ,@(loop for (i j) in pairs collect `(,(ac i j) (abs ,(c i j))))
              ,@(loop for k below 3 collect `(,(box-axis-name "TA~D" k) ,(dot '(dx dy dz) (column "A" k))))
              ,@(loop for k below 3 collect `(,(box-axis-name "TB~D" k) ,(dot '(dx dy dz) (column "B" k))))
              (best -1) (best-sep most-negative-single-float)
              (edge -1) (edge-sep most-negative-single-float) (elx 0.0) (ely 0.0) (elz 0.0))
         (declare (type single-float ,@(loop for (i j) in pairs collect (c i j) collect (ac i j))
                        ta0 ta1 ta2 tb0 tb1 tb2 best-sep edge-sep elx ely elz)
                  (type fixnum best edge))
         (if (block test
               ;; A's faces: A's half-extent along its own axis, B's through |C|
               ,@(loop for k below 3
                       collect `(box-face-axis ,k ,(box-axis-name "TA~D" k) ,(nth k '(ahx ahy ahz)) (bhx bhy bhz)
                                               ,(loop for j below 3 collect (ac k j))))
               (when (>= best-sep reach) (return-from test nil))
               ;; B's faces, taken only when one holds the boxes apart by the axis tolerance
               ;; more than A's best, so that two faces lying on each other keep one reference
               (let ((a-best best) (a-sep best-sep))
                 (declare (type fixnum a-best) (type single-float a-sep))
                 (setf best -1 best-sep most-negative-single-float)
                 ,@(loop for k below 3
                         collect `(box-face-axis ,(+ 3 k) ,(box-axis-name "TB~D" k) ,(nth k '(bhx bhy bhz)) (ahx ahy ahz)
                                                 ,(loop for i below 3 collect (ac i k))))
                 (unless (> best-sep (+ a-sep +box-axis-tolerance+))
                   (setf best a-best best-sep a-sep)))
               (when (>= best-sep reach) (return-from test nil))
               ;; the edge axes A_i x B_j, of length sqrt(C_i1j^2 + C_i2j^2), but for edges
               ;; near parallel
               ,@(loop for (i j) in pairs collect `(box-edge-axis ,i ,j))
               t)
             (values best best-sep edge edge-sep elx ely elz)
             (values -1 0.0 -1 0.0 0.0 0.0 0.0))))))

(declaim (inline box-separating-axis))
(defun box-separating-axis (reach dx dy dz a11 a12 a13 a21 a22 a23 a31 a32 a33 ahx ahy ahz
                            b11 b12 b13 b21 b22 b23 b31 b32 b33 bhx bhy bhz)
  "The separating axis of box A (axes A11 .. A33 row by row, half-extents AHX AHY AHZ) and box B
(the same, B...), A's centre DX DY DZ from B's, as seven values: the face axis along which they
lie farthest apart or overlap least (0-2 A's, 3-5 B's, B's only when it beats A's by the axis
tolerance) and that distance, the edge axis, A's axis I crossed with B's axis J as 3I + J, and
its distance and unit direction; the first value is -1 when some axis holds them at least REACH
apart. #BXCELL"
  (declare (type single-float reach dx dy dz a11 a12 a13 a21 a22 a23 a31 a32 a33 ahx ahy ahz
                 b11 b12 b13 b21 b22 b23 b31 b32 b33 bhx bhy bhz))
  (box-separating-axes))

(defmacro box-edge-point ()
  "Add the point of an edge of box A against an edge of box B (EDGE, along ELX ELY ELZ): midway
between the edges' nearest points, the normal their common perpendicular, from A towards B,
pushing B. Expanded in box-pair-points, whose variables it reads. #BXCELL"
  `(let* ((flip (if (> (+ (* elx dx) (* ely dy) (* elz dz)) 0.0) -1.0 1.0))
         (nx (* flip elx)) (ny (* flip ely)) (nz (* flip elz))
         (ei (floor edge 3)) (ej (mod edge 3))
         (pax acx) (pay acy) (paz acz) (pbx bcx) (pby bcy) (pbz bcz))
    (declare (type single-float flip nx ny nz pax pay paz pbx pby pbz) (type (integer 0 2) ei ej))
    ;; each box's edge farthest along the normal towards the other: its centre
    (dotimes (k 3)
      (unless (= k ei)
        (let* ((cx (nth-of k a11 a12 a13)) (cy (nth-of k a21 a22 a23)) (cz (nth-of k a31 a32 a33))
               (e (* (nth-of k ahx ahy ahz) (if (> (+ (* cx nx) (* cy ny) (* cz nz)) 0.0) 1.0 -1.0))))
          (declare (type single-float cx cy cz e))
          (setf pax (+ pax (* e cx)) pay (+ pay (* e cy)) paz (+ paz (* e cz)))))
      (unless (= k ej)
        (let* ((cx (nth-of k b11 b12 b13)) (cy (nth-of k b21 b22 b23)) (cz (nth-of k b31 b32 b33))
               (e (* (nth-of k bhx bhy bhz) (if (> (+ (* cx nx) (* cy ny) (* cz nz)) 0.0) -1.0 1.0))))
          (declare (type single-float cx cy cz e))
          (setf pbx (+ pbx (* e cx)) pby (+ pby (* e cy)) pbz (+ pbz (* e cz))))))
    ;; the nearest points of the two edges, each held to its edge's length
    (let* ((ux (nth-of ei a11 a12 a13)) (uy (nth-of ei a21 a22 a23)) (uz (nth-of ei a31 a32 a33))
           (vx (nth-of ej b11 b12 b13)) (vy (nth-of ej b21 b22 b23)) (vz (nth-of ej b31 b32 b33))
           (ea (nth-of ei ahx ahy ahz)) (eb (nth-of ej bhx bhy bhz))
           (ddx (- pbx pax)) (ddy (- pby pay)) (ddz (- pbz paz))
           (uv (+ (* ux vx) (* uy vy) (* uz vz)))
           (ud (+ (* ux ddx) (* uy ddy) (* uz ddz)))
           (vd (+ (* vx ddx) (* vy ddy) (* vz ddz)))
           (den (- 1.0 (* uv uv)))
           (sa (if (> den 1e-6) (max (- ea) (min ea (/ (- ud (* uv vd)) den))) 0.0))
           (tb (max (- eb) (min eb (- (* uv sa) vd))))
           (sa (max (- ea) (min ea (+ ud (* uv tb)))))
           (qax (+ pax (* sa ux))) (qay (+ pay (* sa uy))) (qaz (+ paz (* sa uz)))
           (qbx (+ pbx (* tb vx))) (qby (+ pby (* tb vy))) (qbz (+ pbz (* tb vz)))
           (gap (+ (* nx (- qbx qax)) (* ny (- qby qay)) (* nz (- qbz qaz))))
           (mx (* 0.5 (+ qax qbx))) (my (* 0.5 (+ qay qby))) (mz (* 0.5 (+ qaz qbz))))
      (declare (type single-float ux uy uz vx vy vz ea eb ddx ddy ddz uv ud vd den sa tb
                     qax qay qaz qbx qby qbz gap mx my mz))
      (when (< gap reach)
        (add-box-point set row-b owner (logior key-base (ash 7 5) edge) nx ny nz
                       (- mx bcx) (- my bcy) (- mz bcz) gap row-a (- mx acx) (- my acy) (- mz acz))))))
;; A box against the cells:8 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:9]]
(defmacro with-box-roles (&body body)
  "Run BODY with the reference box's numbers bound as R... (centre RCX RCY RCZ, axes R11 .. R33,
half-extents RHX RHY RHZ, row RROW), the incident box's as I..., and the reference face's AXIS:
box B is the reference when ON-B, else box A. Expanded in box-face-points. #BXCELL"
  `(if on-b
       (let ((rcx bcx) (rcy bcy) (rcz bcz) (r11 b11) (r12 b12) (r13 b13) (r21 b21) (r22 b22)
             (r23 b23) (r31 b31) (r32 b32) (r33 b33) (rhx bhx) (rhy bhy) (rhz bhz) (rrow row-b)
             (icx acx) (icy acy) (icz acz) (i11 a11) (i12 a12) (i13 a13) (i21 a21) (i22 a22)
             (i23 a23) (i31 a31) (i32 a32) (i33 a33) (ihx ahx) (ihy ahy) (ihz ahz) (irow row-a)
             (axis (- best 3)))
         ,@body)
       (let ((rcx acx) (rcy acy) (rcz acz) (r11 a11) (r12 a12) (r13 a13) (r21 a21) (r22 a22)
             (r23 a23) (r31 a31) (r32 a32) (r33 a33) (rhx ahx) (rhy ahy) (rhz ahz) (rrow row-a)
             (icx bcx) (icy bcy) (icz bcz) (i11 b11) (i12 b12) (i13 b13) (i21 b21) (i22 b22)
             (i23 b23) (i31 b31) (i32 b32) (i33 b33) (ihx bhx) (ihy bhy) (ihz bhz) (irow row-b)
             (axis best))
         ,@body)))

(defmacro incident-face-corners ()
  "Write into POLY the incident face's four corners, in order around it, in the reference face's
frame (along K1, along K2, and the height over the face), and into IDS their numbers. Expanded in
box-face-points, whose variables it reads. #BXCELL"
  `(progn
     ;; the incident face's corners, in order around it, in the reference face's frame:
     ;; along K1, along K2, and the height over the face
     (dotimes (corner 4)
       (let* ((s1 (if (< 0 corner 3) -1.0 1.0)) (s2 (if (< corner 2) 1.0 -1.0))
              (wx (+ gx (* s1 px) (* s2 qx))) (wy (+ gy (* s1 py) (* s2 qy))) (wz (+ gz (* s1 pz) (* s2 qz)))
              (o (* 3 corner)))
         (declare (type single-float s1 s2 wx wy wz) (type fixnum o))
         (setf (aref poly o) (+ (* wx ux) (* wy uy) (* wz uz))
               (aref poly (+ o 1)) (+ (* wx vx) (* wy vy) (* wz vz))
               (aref poly (+ o 2)) (- (+ (* wx nx) (* wy ny) (* wz nz)) rh)
               (aref ids corner) corner)))))

(defmacro clip-incident-side (plane)
  "Clip the COUNT corners of POLY (numbered in IDS) against the reference face's side PLANE (0 to
3: a <= E1, -a <= E1, b <= E2, -b <= E2) through NEXT and NEXT-IDS, leaving the clipped polygon in
POLY and its COUNT; a side with every corner within it leaves them as they are, in place. DIST
holds each corner's distance past the side. Expanded in clip-incident-face. #BXCELL"
  (let ((along `(aref poly (+ (* 3 i) ,(if (< plane 2) 0 1))))
        (limit (if (< plane 2) 'e1 'e2)))
    `(let ((out 0))
       (declare (type fixnum out))
       ;; a corner within the tolerance of a side is on it, kept as it is, with its own key
       (dotimes (i count)
         (let ((d (- ,(if (evenp plane) along `(- ,along)) ,limit +box-clip-tolerance+)))
           (declare (type single-float d))
           (setf (aref dist i) d)
           (when (> d 0.0) (incf out))))
       (when (plusp out)
         (let ((kept 0))
           (declare (type fixnum kept))
           (dotimes (i count)
             (let* ((j (if (= (1+ i) count) 0 (1+ i)))
                    (oi (* 3 i)) (oj (* 3 j))
                    (di (aref dist i)) (dj (aref dist j)))
               (declare (type fixnum j oi oj) (type single-float di dj))
               (when (<= di 0.0)
                 (let ((o (* 3 kept)))
                   (setf (aref next o) (aref poly oi) (aref next (+ o 1)) (aref poly (+ oi 1))
                         (aref next (+ o 2)) (aref poly (+ oi 2)) (aref next-ids kept) (aref ids i))
                   (incf kept)))
               (when (or (and (<= di 0.0) (> dj 0.0)) (and (> di 0.0) (<= dj 0.0)))
                 ;; the edge crosses the side: the crossing, named by the side and the
                 ;; corner the edge starts from
                 (let ((f (/ di (- di dj))) (o (* 3 kept)))
                   (declare (type single-float f))
                   (dotimes (c 3)
                     (setf (aref next (+ o c))
                           (+ (aref poly (+ oi c)) (* f (- (aref poly (+ oj c)) (aref poly (+ oi c)))))))
                   (setf (aref next-ids kept) (logand 31 (+ ,(+ 4 (* 4 plane)) (logand 3 (aref ids i)))))
                   (incf kept)))))
           (setf count kept)
           (rotatef poly next) (rotatef ids next-ids))))))

(defmacro clip-incident-face ()
  "Clip the COUNT corners of POLY (numbered in IDS) against the reference face's four sides, a <=
E1, -a <= E1, b <= E2, -b <= E2, through NEXT and NEXT-IDS, leaving the clipped polygon in POLY
and its COUNT (clip-incident-side). Expanded in box-face-points, whose variables it reads and
sets. #BXCELL"
  `(let ((dist (make-array 8 :element-type 'single-float)))
     (declare (dynamic-extent dist) (type (simple-array single-float (8)) dist))
     (clip-incident-side 0) (clip-incident-side 1) (clip-incident-side 2) (clip-incident-side 3)))

(defmacro add-incident-points ()
  "Add as points of the incident box each vertex of the clipped POLY nearer than the reach, four
at most (reduce-box-manifold), each keyed by the reference face and its own number. Expanded in
box-face-points, whose variables it reads. #BXCELL"
  `(progn
     ;; each vertex left nearer than the reach is a point on the incident face,
     ;; four at most (reduce-box-manifold)
     (let ((keep (make-array 8 :element-type 'fixnum)) (kept 0))
       (declare (dynamic-extent keep) (type (integer 0 8) kept))
       (dotimes (i count)
         (when (< (aref poly (+ (* 3 i) 2)) reach)
           (setf (aref keep kept) i)
           (incf kept)))
       (when (> kept 4) (setf kept (reduce-box-manifold poly keep kept)))
       (dotimes (q kept)
         (let* ((i (aref keep q))
                (o (* 3 i)) (a (aref poly o)) (b (aref poly (+ o 1))) (gap (aref poly (+ o 2)))
                ;; from the reference centre, and from the incident one
                (fx (+ (* a ux) (* b vx) (* (+ rh gap) nx)))
                (fy (+ (* a uy) (* b vy) (* (+ rh gap) ny)))
                (fz (+ (* a uz) (* b vz) (* (+ rh gap) nz))))
           (declare (type fixnum i o) (type single-float a b gap fx fy fz))
           (add-box-point set irow owner
                          (logior key-base (ash (+ (if on-b 3 0) axis) 5) (aref ids i))
                          nx ny nz (- fx ex) (- fy ey) (- fz ez) gap rrow fx fy fz))))))
;; A box against the cells:9 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:10]]
(defmacro box-face-points ()
  "Add the points of the incident box's face most against the reference face (box B's when the
separating axis BEST is one of B's, else A's), pushed off it along the face's normal: its corners
clipped to the reference face's sides and reduced to four, each with its height over the face as
its gap. Expanded in box-pair-points, whose variables it reads. #BXCELL"
  `(let ((on-b (>= best 3))
         (poly (make-array 24 :element-type 'single-float))
         (next (make-array 24 :element-type 'single-float))
         (ids (make-array 8 :element-type 'fixnum))
         (next-ids (make-array 8 :element-type 'fixnum)))
     (declare (dynamic-extent poly next ids next-ids)
              (type (simple-array single-float (24)) poly next) (type (simple-array fixnum (8)) ids next-ids))
     (with-box-roles
       (let* ((ex (- icx rcx)) (ey (- icy rcy)) (ez (- icz rcz))
              ;; the reference axis, turned towards the incident box, its half-extent,
              ;; and the face's two side axes K1 K2 with theirs
              (lx (nth-of axis r11 r12 r13)) (ly (nth-of axis r21 r22 r23)) (lz (nth-of axis r31 r32 r33))
              (sign (if (>= (+ (* ex lx) (* ey ly) (* ez lz)) 0.0) 1.0 -1.0))
              (nx (* sign lx)) (ny (* sign ly)) (nz (* sign lz))
              (rh (nth-of axis rhx rhy rhz))
              (k1 (if (= axis 0) 1 0)) (k2 (if (= axis 2) 1 2))
              (e1 (nth-of k1 rhx rhy rhz)) (e2 (nth-of k2 rhx rhy rhz))
              (ux (nth-of k1 r11 r12 r13)) (uy (nth-of k1 r21 r22 r23)) (uz (nth-of k1 r31 r32 r33))
              (vx (nth-of k2 r11 r12 r13)) (vy (nth-of k2 r21 r22 r23)) (vz (nth-of k2 r31 r32 r33))
              ;; the incident axis most against N, the face's outward normal and centre
              (c1 (+ (* i11 nx) (* i21 ny) (* i31 nz)))
              (c2 (+ (* i12 nx) (* i22 ny) (* i32 nz)))
              (c3 (+ (* i13 nx) (* i23 ny) (* i33 nz)))
              (m (cond ((and (>= (abs c1) (abs c2)) (>= (abs c1) (abs c3))) 0) ((>= (abs c2) (abs c3)) 1) (t 2)))
              (ms (if (> (nth-of m c1 c2 c3) 0.0) -1.0 1.0))
              (mh (nth-of m ihx ihy ihz))
              (gx (+ ex (* ms mh (nth-of m i11 i12 i13))))
              (gy (+ ey (* ms mh (nth-of m i21 i22 i23))))
              (gz (+ ez (* ms mh (nth-of m i31 i32 i33))))
              (j1 (if (= m 0) 1 0)) (j2 (if (= m 2) 1 2))
              (f1 (nth-of j1 ihx ihy ihz)) (f2 (nth-of j2 ihx ihy ihz))
              (px (* f1 (nth-of j1 i11 i12 i13))) (py (* f1 (nth-of j1 i21 i22 i23))) (pz (* f1 (nth-of j1 i31 i32 i33)))
              (qx (* f2 (nth-of j2 i11 i12 i13))) (qy (* f2 (nth-of j2 i21 i22 i23))) (qz (* f2 (nth-of j2 i31 i32 i33)))
              (count 4))
         (declare (type single-float ex ey ez lx ly lz sign nx ny nz rh e1 e2 ux uy uz vx vy vz
                                     c1 c2 c3 ms mh gx gy gz f1 f2 px py pz qx qy qz)
                  (type (integer 0 2) axis k1 k2 m j1 j2) (type fixnum count))
         (incident-face-corners)
         (clip-incident-face)
         (add-incident-points)))))

(defun box-pair-points (set owner key-base row-a row-b reach
                        acx acy acz aqw aqx aqy aqz ahx ahy ahz
                        bcx bcy bcz bqw bqx bqy bqz bhx bhy bhz)
  "Append to SET, as points found by the box OWNER, the points between box A (centre ACX ACY ACZ,
orientation AQW .. AQZ, half-extents AHX AHY AHZ, solver row ROW-A) and box B (the same, B...),
when they are nearer than REACH along every axis of the separating-axis test: the axis along
which they overlap least (or lie farthest apart) gives the normal. On a face axis the other box's
face most against the reference face, clipped to its sides and reduced to four, gives the points,
each with its height over the reference face as its gap; on an edge axis the edges' nearest points
give one. KEY-BASE with the axis and the vertex's or the edges' feature is a point's key. #BXCELL"
  (declare (type box-set set) (type fixnum owner key-base) (type index row-a row-b)
           (type single-float reach acx acy acz aqw aqx aqy aqz ahx ahy ahz
                 bcx bcy bcz bqw bqx bqy bqz bhx bhy bhz)
           #.+kernel-policy+)
  (multiple-value-bind (a11 a12 a13 a21 a22 a23 a31 a32 a33) (box-axes aqw aqx aqy aqz)
    (multiple-value-bind (b11 b12 b13 b21 b22 b23 b31 b32 b33) (box-axes bqw bqx bqy bqz)
      (declare (type single-float a11 a12 a13 a21 a22 a23 a31 a32 a33 b11 b12 b13 b21 b22 b23 b31 b32 b33))
      (let ((dx (- acx bcx)) (dy (- acy bcy)) (dz (- acz bcz)))
        (declare (type single-float dx dy dz))
        ;; the six face axes and the nine edge axes: how far apart the boxes are along each
        (multiple-value-bind (best best-sep edge edge-sep elx ely elz)
            (box-separating-axis reach dx dy dz a11 a12 a13 a21 a22 a23 a31 a32 a33 ahx ahy ahz
                                 b11 b12 b13 b21 b22 b23 b31 b32 b33 bhx bhy bhz)
          (declare (type fixnum best edge) (type single-float best-sep edge-sep elx ely elz))
          (cond
            ;; some axis holds them at least the reach apart: no point
            ((< best 0))
            ((> edge-sep (+ best-sep +box-axis-tolerance+))
             ;; an edge of A against an edge of B: one point, midway between the edges' nearest
             ;; points, the normal their common perpendicular, from A towards B, pushing B
             (box-edge-point))
            (t
             ;; the reference box R owns the face; the incident box I is pushed off it along N
             (box-face-points)))))))
  set)
;; A box against the cells:10 ends here

;; [[file:../physics.org::#BXCELL][A box against the cells:11]]
(defun grid-awake-boxes (world set n)
  "Bucket the centres of the awake boxes among the first N awake rows of WORLD into SET's grid,
whose items are their rows, in cells of the largest diameter and the margin, and keep their
orientations, in the order of the rows. #BXCELL"
  (declare (type box-set set) (type index n) #.+kernel-policy+)
  (let ((awake (physics-world-awake world)) (count 0))
    (declare (type index count))
    (when (< (length (box-set-grid-rows set)) n)
      (let ((m (max n (* 2 (length (box-set-grid-rows set))))))
        (setf (box-set-grid-rows set) (make-array m :element-type 'fixnum :initial-element 0)
              (box-set-gx set) (make-array m :element-type 'single-float :initial-element 0.0)
              (box-set-gy set) (make-array m :element-type 'single-float :initial-element 0.0)
              (box-set-gz set) (make-array m :element-type 'single-float :initial-element 0.0)
              (box-set-start-q set) (make-array (* 4 m) :element-type 'single-float :initial-element 0.0))
        (hash-grid-reserve (box-set-grid set) m)))
    (let ((rows (box-set-grid-rows set)) (gx (box-set-gx set)) (gy (box-set-gy set)) (gz (box-set-gz set))
          (start-q (box-set-start-q set)))
      (with-body-columns (x y z qw qx qy qz flags) awake
        (dotimes (i n)
          (when (logtest (aref flags i) +flag-box-shape+)
            (setf (aref rows count) i (aref gx count) (aref x i) (aref gy count) (aref y i) (aref gz count) (aref z i)
                  ;; the orientation the turns of the substeps start from (turn-box-orientations)
                  (aref start-q (* 4 count)) (aref qw i) (aref start-q (+ (* 4 count) 1)) (aref qx i)
                  (aref start-q (+ (* 4 count) 2)) (aref qy i) (aref start-q (+ (* 4 count) 3)) (aref qz i))
            (incf count))))
      (build-hash-grid (box-set-grid set)
                       (+ (* 2.0 (f32 (physics-world-max-radius world))) (f32 (physics-world-margin world)))
                       count gx gy gz rows))
    set))

(defun find-box-box-points (world set row reach)
  "Append to SET's points those between the box at awake ROW of WORLD and every other box near
it: each awake box after it in the rows, found in the cells of SET's grid around it, once a pair,
and each sleeping box, found in the sleeping grids and met in the order of the sleeping rows,
which holds still as a cell does (box-pair-points). #BXCELL"
  (declare (type box-set set) (type index row) (type single-float reach) #.+kernel-policy+)
  (let* ((awake (physics-world-awake world)) (sleeping (physics-world-sleeping world))
         (n (body-columns-length awake))
         (ids (physics-world-ids world))
         (hxs (box-set-hx set)) (hys (box-set-hy set)) (hzs (box-set-hz set))
         (grid (box-set-grid set))
         (rmax (f32 (physics-world-max-radius world))))
    (declare (type index n) (type f32-column hxs hys hzs) (type single-float rmax))
    (with-body-columns (x y z qw qx qy qz radius handle) awake
      (let* ((owner (aref handle row)) (slot (handle-index owner))
             (cx (aref x row)) (cy (aref y row)) (cz (aref z row)) (r (aref radius row))
             (aw (aref qw row)) (ax (aref qx row)) (ay (aref qy row)) (az (aref qz row))
             (hx (aref hxs slot)) (hy (aref hys slot)) (hz (aref hzs slot))
             ;; the farthest centre a box may meet this one from, against the grid's cells
             (far (+ r rmax reach))
             (span (ceiling (min 64.0 (* far (hash-grid-inv-cell grid)))))
             (sleep-span (ceiling (min 64.0 (/ far (the single-float (f32 (grid-cell-size world))))))))
        (declare (type fixnum owner) (type single-float cx cy cz r aw ax ay az hx hy hz far)
                 (type (integer 0 64) span sleep-span))
        (flet ((meet (buffer j row-j)
                 ;; the box at row J of BUFFER, at solver row ROW-J
                 (declare (type body-columns buffer) (type index j row-j))
                 (with-body-columns ((ox x) (oy y) (oz z) (ow qw) (oqx qx) (oqy qy) (oqz qz) (orad radius)
                                     (ohandle handle) (oflags flags))
                     buffer
                   (when (logtest (aref oflags j) +flag-box-shape+)
                     (let* ((dx (- (aref ox j) cx)) (dy (- (aref oy j) cy)) (dz (- (aref oz j) cz))
                            (near (+ r (aref orad j) reach)))
                       (when (< (+ (* dx dx) (* dy dy) (* dz dz)) (* near near))
                         (let* ((other (aref ohandle j)) (oslot (handle-index other))
                                (base (logior (ash slot 34) (ash 1 32) (ash oslot 8))))
                           (box-pair-points set owner base row row-j reach
                                            cx cy cz aw ax ay az hx hy hz
                                            (aref ox j) (aref oy j) (aref oz j) (aref ow j) (aref oqx j)
                                            (aref oqy j) (aref oqz j)
                                            (aref hxs oslot) (aref hys oslot) (aref hzs oslot)))))))))
          (do-grid-neighbours (j grid cx cy cz :span span)
            (when (> j row) (meet awake j j)))
          (when (plusp (body-columns-length sleeping))
            (do-sleepers-in-row-order (h world cx cy cz :span sleep-span)
                (let ((s (handle-index h)))
                  (and (= (aref (handle-table-set ids) s) +set-sleeping+)
                       (= (aref (handle-table-generation ids) s) (handle-generation h))
                       (logtest (aref (body-columns-flags sleeping) (aref (handle-table-local ids) s))
                                +flag-box-shape+)))
              (meet sleeping (aref (handle-table-local ids) (handle-index h)) n)))))))
  set)
;; A box against the cells:11 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:1]]
(defconstant +box-jacobian-width+ 12
  "The numbers of a box point's angular parts along its normal: for the first side r × n, then the
world inverse inertia times it, and the same three and three for the second side. #BXSOLV")

(defun box-tangents (nx ny nz)
  "Two unit tangents of the unit normal NX NY NZ, perpendicular to it and to each other, as six
values: the first the normal crossed with the world axis it is least along. #BXSOLV"
  (declare (type single-float nx ny nz))
  (multiple-value-bind (ax ay az)
      (cond ((and (<= (abs nx) (abs ny)) (<= (abs nx) (abs nz))) (values 0.0 (- nz) ny))
            ((<= (abs ny) (abs nz)) (values nz 0.0 (- nx)))
            (t (values (- ny) nx 0.0)))
    (declare (type single-float ax ay az))
    (let ((s (/ 1.0 (fsqrt (+ (* ax ax) (* ay ay) (* az az))))))
      (let ((t1x (* ax s)) (t1y (* ay s)) (t1z (* az s)))
        (values t1x t1y t1z
                (- (* ny t1z) (* nz t1y)) (- (* nz t1x) (* nx t1z)) (- (* nx t1y) (* ny t1x)))))))

(defun prepare-box-points (world h)
  "Find and prepare the points of every awake box of WORLD for the substeps of H: the last step's
points become the old ones, each awake box's are found anew from where it is ([[#BXCELL]]), and
each gets its effective masses, tangents, friction and the box's world inverse inertia; the
boxes' turns are zeroed and their rows excused from the finalize phase's path check. Return the
box set when some point is to be solved, else NIL. #BXSOLV"
  (declare (type single-float h))
  (let* ((set (physics-world-box-bodies world))
         (awake (physics-world-awake world))
         (n (body-columns-length awake)))
    (declare (type box-set set) (type index n))
    ;; this step's points become the old ones
    (rotatef (box-set-points set) (box-set-previous set))
    (rotatef (box-set-first set) (box-set-previous-first set))
    (rotatef (box-set-count set) (box-set-previous-count set))
    (box-point-columns-clear (box-set-points set))
    (box-manifold-columns-clear (box-set-manifolds set))
    (setf (box-set-row-count set) 0 (box-set-dummy set) n)
    (when (plusp (box-set-live set))
      ;; the turns hold three floats for each awake row and for the dummy past them
      (when (< (length (box-set-turns set)) (* 3 (1+ n)))
        (setf (box-set-rows set) (make-array (* 6 (1+ n)) :element-type 'fixnum :initial-element 0)
              (box-set-turns set) (make-array (* 6 (1+ n)) :element-type 'single-float :initial-element 0.0)))
      ;; the turns of the awake rows and of the dummy after them
      (fill (box-set-turns set) 0.0 :end (* 3 (1+ n)))
      (with-world-parameters (margin (zeta damping-ratio) push-max) world
        (let* ((dt (physics-world-current-dt world))
               (gstep (gravity-step world dt))
               (hertz (min (f32 (physics-world-contact-hertz world)) (/ 0.25 h)))
               (near (and (= (physics-world-near-cells-step world) (physics-world-step-count world))
                          (physics-world-near-cells world)))
               (rows (box-set-rows set))
               (posted (plusp (box-columns-length (physics-world-boxes world))))
               (gravity (fsqrt (+ (expt (physics-world-gravity-x world) 2) (expt (physics-world-gravity-y world) 2)
                                  (expt (physics-world-gravity-z world) 2)))))
          (declare (type single-float gravity))
          (setf (box-set-posted set) posted)
          (multiple-value-bind (bias-rate mass-scale impulse-scale) (physics-softness (* 2.0 hertz) zeta h)
            (setf (box-set-bias-rate set) bias-rate (box-set-mass-scale set) mass-scale
                  (box-set-impulse-scale set) impulse-scale (box-set-push-max set) push-max))
          ;; the awake boxes by cell, for the walk over their pairs ([[#BXCELL]]), and the
          ;; awake spheres, for the walk of each box over the spheres near it ([[#BXSPHR]])
          (grid-awake-boxes world set n)
          (grid-awake-spheres world set n dt gstep)
          (multiple-value-bind (threshold hgx hgy hgz) (impact-parameters world)
            (setf (box-set-threshold set) threshold (box-set-hgx set) hgx (box-set-hgy set) hgy
                  (box-set-hgz set) hgz))
          (with-body-columns (vx vy vz flags handle) awake
            (dotimes (i n)
              (when (logtest (aref flags i) +flag-box-shape+)
                (let ((slot (handle-index (aref handle i)))
                      (start (box-point-columns-length (box-set-points set))))
                  (setf (aref rows (box-set-row-count set)) i)
                  (incf (box-set-row-count set))
                  ;; the finalize phase does not hold a box's path as a sphere's ([[#SQU33Z]])
                  (when near (setf (aref near i) most-positive-single-float))
                  (let ((reach (max margin (step-travel (aref vx i) (aref vy i) (aref vz i) dt gstep))))
                    ;; the posted boxes first, so that the cells' points, solved after them, hold ([[#BXPUSH]])
                    (when posted (find-box-posted-points world set i reach dt push-max (* h gravity)))
                    (find-box-points world set i reach)
                    ;; a box faster than its margin sweeps its corners ([[#BXSWEP]])
                    (when (> reach margin) (sweep-box-corners world set i reach))
                    (find-box-box-points world set i reach)
                    ;; the spheres near it ([[#BXSPHR]])
                    (find-box-sphere-points world set i reach dt gstep))
                  ;; its points manifold by manifold
                  (group-box-points set start)
                  (setf (aref (box-set-first set) slot) start
                        (aref (box-set-count set) slot) (- (box-point-columns-length (box-set-points set)) start)))))
            ;; the sleeping boxes, held still, against the awake spheres ([[#BXSPHR]])
            (find-sleeping-box-sphere-points world set margin dt gstep)))
        ;; a braced side is static to a much heavier body on it ([[#BXBRAC]])
        (brace-box-points world set)
        (prepare-box-point-masses world set)
        (when (box-set-posted set) (cap-posted-box-points set))
        (prepare-box-manifolds set margin)))
    (setf (box-set-solving set) (plusp (box-point-columns-length (box-set-points set))))
    (and (box-set-solving set) set)))
;; Box points in the substeps:1 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:2]]
(defun box-row-inertia (awake set i)
  "The inverse mass of the box at awake row I of AWAKE, a buffer of SET's world, and its world
inverse inertia R D^-1 R^T as six entries 11 12 13 22 23 33: seven values, zeros for the dummy row
past the awake ones, and for a sphere its scalar inverse inertia on the diagonal. #BXSOLV"
  (declare (type body-columns awake) (type box-set set) (type index i) #.+kernel-policy+)
  (cond
    ((>= i (body-columns-length awake))
      (values 0.0 0.0 0.0 0.0 0.0 0.0 0.0))
    ;; a sphere met by a box ([[#BXSPHR]]): its scalar inverse inertia on the diagonal
    ((not (logtest (aref (body-columns-flags awake) i) +flag-box-shape+))
     (let ((ii (aref (body-columns-inverse-inertia awake) i)))
       (values (aref (body-columns-inverse-mass awake) i) ii 0.0 0.0 ii 0.0 ii)))
    (t
      (with-body-columns (qw qx qy qz inverse-mass handle) awake
        (let* ((slot (handle-index (aref handle i)))
               (m (aref inverse-mass i))
               (hx (aref (box-set-hx set) slot)) (hy (aref (box-set-hy set) slot)) (hz (aref (box-set-hz set) slot))
               ;; the inverse inertia in the box's frame: 3 / (m (b^2 + c^2)) and its like
               (dx (/ (* 3.0 m) (+ (* hy hy) (* hz hz))))
               (dy (/ (* 3.0 m) (+ (* hx hx) (* hz hz))))
               (dz (/ (* 3.0 m) (+ (* hx hx) (* hy hy)))))
          (declare (type single-float m hx hy hz dx dy dz))
          (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33)
              (box-axes (aref qw i) (aref qx i) (aref qy i) (aref qz i))
            (declare (type single-float r11 r12 r13 r21 r22 r23 r31 r32 r33))
            (values m
                    (+ (* r11 r11 dx) (* r12 r12 dy) (* r13 r13 dz))
                    (+ (* r11 r21 dx) (* r12 r22 dy) (* r13 r23 dz))
                    (+ (* r11 r31 dx) (* r12 r32 dy) (* r13 r33 dz))
                    (+ (* r21 r21 dx) (* r22 r22 dy) (* r23 r23 dz))
                    (+ (* r21 r31 dx) (* r22 r32 dy) (* r23 r33 dz))
                    (+ (* r31 r31 dx) (* r32 r32 dy) (* r33 r33 dz)))))))))

(defun fill-box-row-inertias (world set)
  "Write into SET's inertias, eight floats a row, each awake row's inverse mass and world inverse
inertia (box-row-inertia) and, past them, the dummy row's zeros. #BXSOLV"
  (declare (type box-set set) #.+kernel-policy+)
  (let* ((awake (physics-world-awake world)) (n (body-columns-length awake)))
    (declare (type index n))
    (when (< (length (box-set-inertias set)) (* 8 (1+ n)))
      (setf (box-set-inertias set) (make-array (* 16 (1+ n)) :element-type 'single-float :initial-element 0.0)))
    (let ((table (box-set-inertias set)))
      (declare (type f32-column table))
      (dotimes (i (1+ n))
        (multiple-value-bind (m e11 e12 e13 e22 e23 e33) (box-row-inertia awake set i)
          (let ((o (* 8 i)))
            (declare (type index o))
            (setf (aref table o) m (aref table (+ o 1)) e11 (aref table (+ o 2)) e12 (aref table (+ o 3)) e13
                  (aref table (+ o 4)) e22 (aref table (+ o 5)) e23 (aref table (+ o 6)) e33))))))
  set)

(defmacro with-box-point-inertias ((k) &body body)
  "Run BODY with M and MB the inverse masses of box point K's two sides and (ia I) and (ib I) the
entries of their world inverse inertias, I from 1 to 6 for 11 12 13 22 23 33, read from TABLE,
the box set's rows' inertias, eight floats a row, DUMMY the dummy row past the awake ones. Expanded
inside with-box-point-columns of ROW and ROW-B. #BXSOLV"
  `(let* ((at-a (* 8 (min (aref row ,k) dummy))) (at-b (* 8 (min (aref row-b ,k) dummy)))
          (m (aref table at-a)) (mb (aref table at-b)))
     (declare (type index at-a at-b) (type single-float m mb) (ignorable m mb))
     (macrolet ((ia (i) `(aref table (+ at-a ,i))) (ib (i) `(aref table (+ at-b ,i))))
       ,@body)))
;; Box points in the substeps:2 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:3]]
(defun box-point-directions (points k table dummy)
  "Write box point K of POINTS's angular parts along its normal, r x n and I^-1 (r x n) on each
side, and its effective mass along it, from its levers, normal, and its sides' inverse masses and
world inverse inertias in TABLE, the rows' (DUMMY the dummy row). #BXSOLV"
  (declare (type box-point-columns points) (type index k dummy) (type f32-column table) #.+kernel-policy+)
  (with-box-point-columns (row row-b nx ny nz rx ry rz sx sy sz normal-mass jacobian) points
    (let ((o (* +box-jacobian-width+ k)) (ux (aref nx k)) (uy (aref ny k)) (uz (aref nz k)))
      (declare (type index o) (type single-float ux uy uz))
      (flet ((lever (at lx ly lz e11 e12 e13 e22 e23 e33)
               ;; r x n at AT, I^-1 (r x n) three places on, and their product
               (declare (type index at) (type single-float lx ly lz e11 e12 e13 e22 e23 e33))
               (let* ((px (- (* ly uz) (* lz uy))) (py (- (* lz ux) (* lx uz))) (pz (- (* lx uy) (* ly ux)))
                      (qx (+ (* e11 px) (* e12 py) (* e13 pz)))
                      (qy (+ (* e12 px) (* e22 py) (* e23 pz)))
                      (qz (+ (* e13 px) (* e23 py) (* e33 pz))))
                 (setf (aref jacobian at) px (aref jacobian (+ at 1)) py (aref jacobian (+ at 2)) pz
                       (aref jacobian (+ at 3)) qx (aref jacobian (+ at 4)) qy (aref jacobian (+ at 5)) qz)
                 (+ (* px qx) (* py qy) (* pz qz)))))
        (declare (inline lever))
        ;; 1 / (1/m_a + 1/m_b + (r_a x n) . Ia^-1 (r_a x n) + (r_b x n) . Ib^-1 (r_b x n))
        (with-box-point-inertias (k)
          (let ((kk (+ m mb
                       (lever o (aref rx k) (aref ry k) (aref rz k) (ia 1) (ia 2) (ia 3) (ia 4) (ia 5) (ia 6))
                       (lever (+ o 6) (aref sx k) (aref sy k) (aref sz k) (ib 1) (ib 2) (ib 3) (ib 4) (ib 5) (ib 6)))))
            (declare (type single-float kk))
            (setf (aref normal-mass k) (if (> kk 0.0) (/ 1.0 kk) 0.0)))))))
  nil)

(defun prepare-box-point-masses (world set)
  "Write each awake row's inverse mass and world inverse inertia into SET's table of them
(fill-box-row-inertias), and each of SET's points' tangents, its angular parts along its normal on each side (r x n and I^-1 (r x n)), its normal's effective
mass and friction (the larger side's, the mean of two boxes'); each gap gains the slop, so a
box rests a slop deep as a sphere does. #BXSOLV"
  (declare (type box-set set) #.+kernel-policy+)
  (let ((awake (physics-world-awake world)) (points (box-set-points set))
        (slop (f32 (physics-world-slop world)))
        (table (box-set-inertias (fill-box-row-inertias world set))))
    (declare (type single-float slop) (type f32-column table))
    (setf (box-set-bouncy set) nil)
    (with-body-columns ((fr friction) (re restitution)) awake
      (with-box-point-columns (row row-b nx ny nz t1x t1y t1z t2x t2y t2z friction
                               separation restitution pushed impact-speed bounce)
          points
        (dotimes (k (box-point-columns-length points))
          (setf (aref separation k) (+ (aref separation k) slop))
          ;; the larger restitution of the sides that move, as a sphere contact's ([[#PR3PAR]])
          (let ((a (aref row k)) (b (aref row-b k)) (n (body-columns-length awake)))
            (declare (type index a b n))
            (setf (aref restitution k) (max (if (< a n) (aref re a) 0.0) (if (< b n) (aref re b) 0.0))
                  (aref pushed k) 0.0 (aref impact-speed k) 0.0 (aref bounce k) 0.0)
            (when (> (aref restitution k) 0.0) (setf (box-set-bouncy set) t)))
          (let ((a (aref row k)) (b (aref row-b k)) (n (body-columns-length awake)))
            (declare (type index a b n))
            (setf (aref friction k) (cond ((>= b n) (aref fr a))
                                          ((>= a n) (aref fr b))
                                          (t (fsqrt (* (aref fr a) (aref fr b)))))))
          (multiple-value-bind (ax ay az bx by bz) (box-tangents (aref nx k) (aref ny k) (aref nz k))
            (setf (aref t1x k) ax (aref t1y k) ay (aref t1z k) az (aref t2x k) bx (aref t2y k) by (aref t2z k) bz))
          (box-point-directions points k table (body-columns-length awake))))))
  set)
;; Box points in the substeps:3 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:4]]
(declaim (inline box-points-one-manifold-p))
(defun box-points-one-manifold-p (points j k)
  "Whether box points J and K of POINTS lie in one manifold: found by one box, between the same
two sides, along the same normal, and both against one posted box's motion or neither. #BXSOLV"
  (declare (type box-point-columns points) (type index j k) #.+kernel-policy+)
  (with-box-point-columns (row row-b handle nx ny nz kvx kvy kvz push-cap) points
    (and (= (aref row-b j) (aref row-b k)) (= (aref row j) (aref row k)) (= (aref handle j) (aref handle k))
         (= (aref nx j) (aref nx k)) (= (aref ny j) (aref ny k)) (= (aref nz j) (aref nz k))
         (= (aref kvx j) (aref kvx k)) (= (aref kvy j) (aref kvy k)) (= (aref kvz j) (aref kvz k))
         (eq (< (aref push-cap j) most-positive-single-float) (< (aref push-cap k) most-positive-single-float)))))

(defun group-box-points (set start)
  "Lay the points of SET from START to the end, those one box found, manifold by manifold: each
manifold where its first point was found, its points in the order they were found, so the
manifolds against posted boxes stay before those against the cells ([[#BXPUSH]]). Points found
manifold by manifold already, the common case, move nothing. #BXSOLV"
  (declare (type box-set set) (type index start) #.+kernel-policy+)
  (let* ((points (box-set-points set)) (end (box-point-columns-length points)))
    (declare (type index end))
    (flet ((head-p (k)
             ;; the first point of its manifold in the range
             (loop for j of-type index from start below k never (box-points-one-manifold-p points j k))))
      (when (loop for k of-type index from (1+ start) below end
                  thereis (and (not (box-points-one-manifold-p points (1- k) k)) (not (head-p k))))
        (let ((scratch (box-point-columns-ensure-capacity (box-set-scratch set) (- end start))) (to 0))
          (declare (type index to))
          (loop for h of-type index from start below end
                when (head-p h)
                  do (loop for k of-type index from h below end
                           when (box-points-one-manifold-p points h k)
                             do (box-point-columns-copy-row points k scratch to) (incf to)))
          (dotimes (i to) (box-point-columns-copy-row scratch i points (+ start i)))))))
  set)
;; Box points in the substeps:4 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:5]]
(defun box-manifold-centre (points manifolds mi inv-tau)
  "Write manifold MI's friction centre, its points' first levers and second levers averaged with
Box3D's weights, 1 for a gap up to the margin (1/INV-TAU), falling to nothing at twice it, so a
point that only may touch moves the centre little; its points' lever arms, their distances from
it; and the plain mean of its first levers. #BXSOLV"
  (declare (type box-point-columns points) (type box-manifold-columns manifolds) (type index mi)
           (type single-float inv-tau) #.+kernel-policy+)
  (with-box-point-columns (rx ry rz sx sy sz separation lever-arm) points
    (with-box-manifold-columns ((mfirst first) (mcount count) cax cay caz cbx cby cbz ox oy oz) manifolds
      (let* ((first (aref mfirst mi)) (end (+ first (aref mcount mi)))
             (ws 0.0) (ax 0.0) (ay 0.0) (az 0.0) (bx 0.0) (by 0.0) (bz 0.0) (mx 0.0) (my 0.0) (mz 0.0))
        (declare (type index first end) (type single-float ws ax ay az bx by bz mx my mz))
        (loop for k of-type index from first below end
              do (let ((w (min 1.0 (max 1e-10 (- 2.0 (* (aref separation k) inv-tau))))))
                   (declare (type single-float w))
                   (setf ws (+ ws w)
                         ax (+ ax (* w (aref rx k))) ay (+ ay (* w (aref ry k))) az (+ az (* w (aref rz k)))
                         bx (+ bx (* w (aref sx k))) by (+ by (* w (aref sy k))) bz (+ bz (* w (aref sz k)))
                         mx (+ mx (aref rx k)) my (+ my (aref ry k)) mz (+ mz (aref rz k)))))
        (let ((iw (/ 1.0 ws)) (in (/ 1.0 (float (- end first) 1.0))))
          (declare (type single-float iw in))
          (setf (aref cax mi) (* ax iw) (aref cay mi) (* ay iw) (aref caz mi) (* az iw)
                (aref cbx mi) (* bx iw) (aref cby mi) (* by iw) (aref cbz mi) (* bz iw)
                (aref ox mi) (* mx in) (aref oy mi) (* my in) (aref oz mi) (* mz in)))
        (loop for k of-type index from first below end
              do (let ((dx (- (aref rx k) (aref cax mi))) (dy (- (aref ry k) (aref cay mi)))
                       (dz (- (aref rz k) (aref caz mi))))
                   (declare (type single-float dx dy dz))
                   (setf (aref lever-arm k) (fsqrt (+ (* dx dx) (* dy dy) (* dz dz)))))))))
  nil)

(defun box-manifold-masses (points manifolds mi table dummy)
  "Write manifold MI's angular parts at its friction centre, c x t and I^-1 (c x t) for both
tangents on each side and I^-1 n on each, from its first point's directions and inertias; the
inverse of its 2 x 2 tangent mass, K11 = 1/m_a + 1/m_b + (c_a x t1) . Ia^-1 (c_a x t1) + (c_b x
t1) . Ib^-1 (c_b x t1), K12 the same of t1 and t2 (zero when K is singular); its twist mass
1/(n . Ia^-1 n + n . Ib^-1 n); and its friction, its first point's. The sides' inverse masses and
inertias are read from TABLE, the rows' (DUMMY the dummy row). #BXSOLV"
  (declare (type box-point-columns points) (type box-manifold-columns manifolds) (type index mi dummy)
           (type f32-column table) #.+kernel-policy+)
  (with-box-point-columns (row row-b nx ny nz t1x t1y t1z t2x t2y t2z friction) points
    (with-box-manifold-columns ((mfirst first) (mfriction friction) cax cay caz cbx cby cbz k11 k12 k22
                                twist-mass (mj jacobian))
        manifolds
      (with-box-point-inertias ((aref mfirst mi))
        (let ((k (aref mfirst mi)) (o (* 30 mi)))
          (declare (type index k o))
          (flet ((part (at lx ly lz ux uy uz e11 e12 e13 e22 e23 e33)
                   ;; l x u at AT, I^-1 (l x u) six places on
                   (declare (type index at) (type single-float lx ly lz ux uy uz e11 e12 e13 e22 e23 e33))
                   (let ((px (- (* ly uz) (* lz uy))) (py (- (* lz ux) (* lx uz))) (pz (- (* lx uy) (* ly ux))))
                     (declare (type single-float px py pz))
                     (setf (aref mj at) px (aref mj (+ at 1)) py (aref mj (+ at 2)) pz
                           (aref mj (+ at 6)) (+ (* e11 px) (* e12 py) (* e13 pz))
                           (aref mj (+ at 7)) (+ (* e12 px) (* e22 py) (* e23 pz))
                           (aref mj (+ at 8)) (+ (* e13 px) (* e23 py) (* e33 pz)))))
                 (dot (a b) (declare (type index a b))
                   (+ (* (aref mj a) (aref mj b)) (* (aref mj (+ a 1)) (aref mj (+ b 1))) (* (aref mj (+ a 2)) (aref mj (+ b 2))))))
            (declare (inline part dot))
            (macrolet ((side (at lx ly lz e11 e12 e13 e22 e23 e33)
                         `(progn (part ,at ,lx ,ly ,lz (aref t1x k) (aref t1y k) (aref t1z k) ,e11 ,e12 ,e13 ,e22 ,e23 ,e33)
                                 (part (+ ,at 3) ,lx ,ly ,lz (aref t2x k) (aref t2y k) (aref t2z k) ,e11 ,e12 ,e13 ,e22 ,e23 ,e33))))
              (side o (aref cax mi) (aref cay mi) (aref caz mi) (ia 1) (ia 2) (ia 3) (ia 4) (ia 5) (ia 6))
              (side (+ o 12) (aref cbx mi) (aref cby mi) (aref cbz mi) (ib 1) (ib 2) (ib 3) (ib 4) (ib 5) (ib 6)))
            (let ((n1 (aref nx k)) (n2 (aref ny k)) (n3 (aref nz k)))
              (declare (type single-float n1 n2 n3))
              (setf (aref mj (+ o 24)) (+ (* (ia 1) n1) (* (ia 2) n2) (* (ia 3) n3))
                    (aref mj (+ o 25)) (+ (* (ia 2) n1) (* (ia 4) n2) (* (ia 5) n3))
                    (aref mj (+ o 26)) (+ (* (ia 3) n1) (* (ia 5) n2) (* (ia 6) n3))
                    (aref mj (+ o 27)) (+ (* (ib 1) n1) (* (ib 2) n2) (* (ib 3) n3))
                    (aref mj (+ o 28)) (+ (* (ib 2) n1) (* (ib 4) n2) (* (ib 5) n3))
                    (aref mj (+ o 29)) (+ (* (ib 3) n1) (* (ib 5) n2) (* (ib 6) n3)))
              (let* ((m (+ m mb))
                     (a11 (+ m (dot o (+ o 6)) (dot (+ o 12) (+ o 18))))
                     (a22 (+ m (dot (+ o 3) (+ o 9)) (dot (+ o 15) (+ o 21))))
                     (a12 (+ (dot o (+ o 9)) (dot (+ o 12) (+ o 21))))
                     (det (- (* a11 a22) (* a12 a12)))
                     (inv (if (> det 0.0) (/ 1.0 det) 0.0))
                     (tk (+ (* n1 (aref mj (+ o 24))) (* n2 (aref mj (+ o 25))) (* n3 (aref mj (+ o 26)))
                            (* n1 (aref mj (+ o 27))) (* n2 (aref mj (+ o 28))) (* n3 (aref mj (+ o 29))))))
                (declare (type single-float m a11 a22 a12 det inv tk))
                (setf (aref k11 mi) (* a22 inv) (aref k12 mi) (- (* a12 inv)) (aref k22 mi) (* a11 inv)
                      (aref twist-mass mi) (if (> tk 0.0) (/ 1.0 tk) 0.0)
                      (aref mfriction mi) (aref friction k)))))))))
  nil)

(defmacro do-box-manifold-shares ((mi k a b) &body body)
  "Run BODY for each point K of manifold MI with A and B its first lever less the manifold's mean
lever along the two tangents; expanded inside with-box-point-columns of RX RY RZ and T1X .. T2Z
and with-box-manifold-columns of (MFIRST FIRST), (MCOUNT COUNT), OX, OY and OZ. #BXSOLV"
  `(loop for ,k of-type index from (aref mfirst ,mi) below (+ (aref mfirst ,mi) (aref mcount ,mi))
         do (let* ((dx (- (aref rx ,k) (aref ox ,mi))) (dy (- (aref ry ,k) (aref oy ,mi))) (dz (- (aref rz ,k) (aref oz ,mi)))
                   (,a (+ (* dx (aref t1x ,k)) (* dy (aref t1y ,k)) (* dz (aref t1z ,k))))
                   (,b (+ (* dx (aref t2x ,k)) (* dy (aref t2y ,k)) (* dz (aref t2z ,k)))))
              (declare (type single-float dx dy dz ,a ,b))
              ,@body)))
;; Box points in the substeps:5 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:6]]
(defun prepare-box-manifolds (set margin)
  "Gather SET's points, laid manifold by manifold (group-box-points), into its manifolds: each run
of points of one manifold is one, with its friction centre (box-manifold-centre, MARGIN the
speculative margin), masses (box-manifold-masses) and the friction and twist impulses its points
carried from the last step as shares (store-box-manifold-impulses): F the sum of the shares,
the twist the sum of their moments about the mean lever. #BXSOLV"
  (declare (type box-set set) (type single-float margin) #.+kernel-policy+)
  (let* ((points (box-set-points set)) (manifolds (box-set-manifolds set))
         (n (box-point-columns-length points)) (inv-tau (/ 1.0 (max margin 1e-6))) (k 0))
    (declare (type index n k) (type single-float inv-tau))
    (box-manifold-columns-clear manifolds)
    (loop while (< k n)
          do (let ((end (1+ k)) (mi (box-manifold-columns-append manifolds)))
               (declare (type index end mi))
               (loop while (and (< end n) (box-points-one-manifold-p points k end)) do (incf end))
               (setf (aref (box-manifold-columns-first manifolds) mi) k
                     (aref (box-manifold-columns-count manifolds) mi) (- end k))
               (box-manifold-centre points manifolds mi inv-tau)
               (box-manifold-masses points manifolds mi (box-set-inertias set) (box-set-dummy set))
               (with-box-point-columns (rx ry rz t1x t1y t1z t2x t2y t2z tangent-impulse-1 tangent-impulse-2) points
                 (with-box-manifold-columns ((mfirst first) (mcount count) ox oy oz friction-impulse-1
                                             friction-impulse-2 twist-impulse)
                     manifolds
                   (let ((f1 0.0) (f2 0.0) (tw 0.0))
                     (declare (type single-float f1 f2 tw))
                     (do-box-manifold-shares (mi j a b)
                       (let ((s1 (aref tangent-impulse-1 j)) (s2 (aref tangent-impulse-2 j)))
                         (setf f1 (+ f1 s1) f2 (+ f2 s2) tw (+ tw (- (* a s2) (* b s1))))))
                     (setf (aref friction-impulse-1 mi) f1 (aref friction-impulse-2 mi) f2
                           (aref twist-impulse mi) tw))))
               (setf k end))))
  set)

(defun store-box-manifold-impulses (set)
  "After the substeps, write each of SET's manifolds' friction and twist impulses into its points
as shares, what their keys carry into the next step (add-box-point) and a snapshot holds: a
point's share is F/N + tw (a t2 - b t1)/D, F the friction impulse, N the points, tw the twist,
a and b the point's first lever less the mean one along the tangents and D the sum of a^2 + b^2
(the twist left out when D is zero, a single point's), so the shares sum to F and their moments
about the mean lever to tw. #BXSOLV"
  (declare (type box-set set) #.+kernel-policy+)
  (let ((points (box-set-points set)) (manifolds (box-set-manifolds set)))
    (with-box-point-columns (rx ry rz t1x t1y t1z t2x t2y t2z tangent-impulse-1 tangent-impulse-2) points
      (with-box-manifold-columns ((mfirst first) (mcount count) ox oy oz friction-impulse-1
                                  friction-impulse-2 twist-impulse)
          manifolds
        (dotimes (mi (box-manifold-columns-length manifolds))
          (let ((d 0.0) (in (/ 1.0 (float (aref mcount mi) 1.0))))
            (declare (type single-float d in))
            (do-box-manifold-shares (mi k a b) (setf d (+ d (* a a) (* b b))))
            (let ((f1 (* in (aref friction-impulse-1 mi))) (f2 (* in (aref friction-impulse-2 mi)))
                  (tw (if (> d 0.0) (/ (aref twist-impulse mi) d) 0.0)))
              (declare (type single-float f1 f2 tw))
              (do-box-manifold-shares (mi k a b)
                (setf (aref tangent-impulse-1 k) (- f1 (* tw b)) (aref tangent-impulse-2 k) (+ f2 (* tw a))))))))))
  nil)
;; Box points in the substeps:6 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:7]]
(defmacro with-box-point ((v k) &body body)
  "Run BODY for box point K, its columns bound by with-box-point-columns, over the solver's
velocities V, with O and OB the two sides' solver rows, (push! PX PY PZ) the impulse P applied at
the point, P/m and I^-1 (r x P) to the first side and their opposites to the second, and
(point-velocity) the first side's point velocity less the second's, v + w x r, as three values;
M, MB, (ia I) and (ib I) the sides' inverse masses and inertias (with-box-point-inertias). #BXSOLV"
  `(let ((o (solver-row (aref row ,k))) (ob (solver-row (aref row-b ,k))))
     (declare (type index o ob))
     (with-box-point-inertias (,k)
       (flet ((push! (px py pz)
                (declare (type single-float px py pz))
                (let* ((tx (- (* (aref ry ,k) pz) (* (aref rz ,k) py)))
                       (ty (- (* (aref rz ,k) px) (* (aref rx ,k) pz)))
                       (tz (- (* (aref rx ,k) py) (* (aref ry ,k) px)))
                       (ux (- (* (aref sy ,k) pz) (* (aref sz ,k) py)))
                       (uy (- (* (aref sz ,k) px) (* (aref sx ,k) pz)))
                       (uz (- (* (aref sx ,k) py) (* (aref sy ,k) px))))
                  (setf (aref ,v o) (+ (aref ,v o) (* m px))
                        (aref ,v (+ o 1)) (+ (aref ,v (+ o 1)) (* m py))
                        (aref ,v (+ o 2)) (+ (aref ,v (+ o 2)) (* m pz))
                        (aref ,v (+ o 3)) (+ (aref ,v (+ o 3)) (+ (* (ia 1) tx) (* (ia 2) ty) (* (ia 3) tz)))
                        (aref ,v (+ o 4)) (+ (aref ,v (+ o 4)) (+ (* (ia 2) tx) (* (ia 4) ty) (* (ia 5) tz)))
                        (aref ,v (+ o 5)) (+ (aref ,v (+ o 5)) (+ (* (ia 3) tx) (* (ia 5) ty) (* (ia 6) tz))))
                  ;; the dummy row, a cell's or a sleeper's, stays zero
                  (when (> mb 0.0)
                    (setf (aref ,v ob) (- (aref ,v ob) (* mb px))
                          (aref ,v (+ ob 1)) (- (aref ,v (+ ob 1)) (* mb py))
                          (aref ,v (+ ob 2)) (- (aref ,v (+ ob 2)) (* mb pz))
                          (aref ,v (+ ob 3)) (- (aref ,v (+ ob 3)) (+ (* (ib 1) ux) (* (ib 2) uy) (* (ib 3) uz)))
                          (aref ,v (+ ob 4)) (- (aref ,v (+ ob 4)) (+ (* (ib 2) ux) (* (ib 4) uy) (* (ib 5) uz)))
                          (aref ,v (+ ob 5)) (- (aref ,v (+ ob 5)) (+ (* (ib 3) ux) (* (ib 5) uy) (* (ib 6) uz)))))))
              (point-velocity ()
                ;; (v + w x r) of the first side less that of the second, less a posted box's
                ;; velocity (KVX KVY KVZ, zero but for a point against a posted box: x - 0.0 is x)
                (values (- (- (+ (aref ,v o) (- (* (aref ,v (+ o 4)) (aref rz ,k)) (* (aref ,v (+ o 5)) (aref ry ,k))))
                              (+ (aref ,v ob) (- (* (aref ,v (+ ob 4)) (aref sz ,k)) (* (aref ,v (+ ob 5)) (aref sy ,k)))))
                           (aref kvx ,k))
                        (- (- (+ (aref ,v (+ o 1)) (- (* (aref ,v (+ o 5)) (aref rx ,k)) (* (aref ,v (+ o 3)) (aref rz ,k))))
                              (+ (aref ,v (+ ob 1)) (- (* (aref ,v (+ ob 5)) (aref sx ,k)) (* (aref ,v (+ ob 3)) (aref sz ,k)))))
                           (aref kvy ,k))
                        (- (- (+ (aref ,v (+ o 2)) (- (* (aref ,v (+ o 3)) (aref ry ,k)) (* (aref ,v (+ o 4)) (aref rx ,k))))
                              (+ (aref ,v (+ ob 2)) (- (* (aref ,v (+ ob 3)) (aref sy ,k)) (* (aref ,v (+ ob 4)) (aref sx ,k)))))
                           (aref kvz ,k)))))
         (declare (inline push! point-velocity) (ignorable #'point-velocity #'push!))
         ,@body))))

(defmacro with-box-point-sides ((v k) &body body)
  "Run BODY for box point K over the solver's velocities V with the two sides' velocities and
spins as locals, AVX AVY AVZ AWX AWY AWZ and BVX .. BWZ, read once; (jac I) the point's angular part
I ([[#BXSOLV]]'s +box-jacobian-width+); (apply! PX PY PZ WA WB) the impulse P at the point, P
times the inverse mass added to the first side's velocity and taken from the second's, and the
spin changes WA and WB, each three forms, added to the first and taken from the second; the
sides are written back after BODY, the second only when it moves. Expanded inside
with-box-point-columns of ROW, ROW-B and JACOBIAN, over TABLE, the rows' inverse masses, and
DUMMY. #BXSOLV"
  `(let* ((o (solver-row (aref row ,k))) (ob (solver-row (aref row-b ,k)))
          (jo (* +box-jacobian-width+ ,k))
          (m (aref table (* 8 (min (aref row ,k) dummy)))) (mb (aref table (* 8 (min (aref row-b ,k) dummy))))
          (avx (aref ,v o)) (avy (aref ,v (+ o 1))) (avz (aref ,v (+ o 2)))
          (awx (aref ,v (+ o 3))) (awy (aref ,v (+ o 4))) (awz (aref ,v (+ o 5)))
          (bvx (aref ,v ob)) (bvy (aref ,v (+ ob 1))) (bvz (aref ,v (+ ob 2)))
          (bwx (aref ,v (+ ob 3))) (bwy (aref ,v (+ ob 4))) (bwz (aref ,v (+ ob 5))))
     (declare (type index o ob jo) (type single-float m mb avx avy avz awx awy awz bvx bvy bvz bwx bwy bwz)
              (ignorable jo))
     (macrolet ((jac (i) `(aref jacobian (+ jo ,i)))
                (apply! (px py pz (wax way waz) (wbx wby wbz))
                  `(let ((px ,px) (py ,py) (pz ,pz))
                     (declare (type single-float px py pz))
                     (setf avx (+ avx (* m px)) avy (+ avy (* m py)) avz (+ avz (* m pz))
                           awx (+ awx ,wax) awy (+ awy ,way) awz (+ awz ,waz)
                           bvx (- bvx (* mb px)) bvy (- bvy (* mb py)) bvz (- bvz (* mb pz))
                           bwx (- bwx ,wbx) bwy (- bwy ,wby) bwz (- bwz ,wbz)))))
       ,@body
       (setf (aref ,v o) avx (aref ,v (+ o 1)) avy (aref ,v (+ o 2)) avz
             (aref ,v (+ o 3)) awx (aref ,v (+ o 4)) awy (aref ,v (+ o 5)) awz)
       ;; the dummy row, a cell's or a sleeper's, stays zero
       (when (> mb 0.0)
         (setf (aref ,v ob) bvx (aref ,v (+ ob 1)) bvy (aref ,v (+ ob 2)) bvz
               (aref ,v (+ ob 3)) bwx (aref ,v (+ ob 4)) bwy (aref ,v (+ ob 5)) bwz)))))

(defmacro box-point-impact-speed (vn s positive biased inv-h dv)
  "The speed at which a box point whose normal velocity is VN and whose gap is S strikes, as a
sphere row's ([[#R3ST1T]]): VN taken at this instant of the substep (the solve pass, BIASED, runs
before its positions move, the relax pass after), and grown by the fall through the gap still
open, DV the change of VN over a substep under gravity. #BXSOLV"
  `(let* ((half (* 0.5 ,dv))
          (c (if ,biased (- ,vn half) (+ ,vn half)))
          (u2 (- (* c c) (* (* (* 2.0 ,dv) (if ,positive ,s 0.0)) ,inv-h))))
     (declare (type single-float half c u2))
     (fsqrt (if (> u2 0.0) u2 0.0))))

(defmacro with-box-manifold-friction ((mi) &body body)
  "Run BODY for manifold MI with MO its offset among the manifolds' angular parts, (mj I) its
angular part I, and F1 F2 TW its friction and twist impulses; expanded inside
with-box-manifold-columns of (MJACOBIAN JACOBIAN), FRICTION-IMPULSE-1, FRICTION-IMPULSE-2 and
TWIST-IMPULSE. #BXSOLV"
  `(let* ((mo (* 30 ,mi))
          (f1 (aref friction-impulse-1 ,mi)) (f2 (aref friction-impulse-2 ,mi)) (tw (aref twist-impulse ,mi)))
     (declare (type index mo) (type single-float f1 f2 tw) (ignorable f1 f2 tw))
     (macrolet ((mj (i) `(aref mjacobian (+ mo ,i))))
       ,@body)))
;; Box points in the substeps:7 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:8]]
(defun warm-start-box-points (set v)
  "Apply every box manifold's carried impulses again, at the start of a substep: each point's
normal impulse at the point, then the manifold's friction at its centre and its twist. #BXSOLV"
  (declare (type box-set set) (type f32-column v) #.+kernel-policy+)
  (let ((points (box-set-points set)) (manifolds (box-set-manifolds set))
        (table (box-set-inertias set)) (dummy (box-set-dummy set)))
    (declare (type f32-column table) (type index dummy))
    (with-box-point-columns (row row-b nx ny nz t1x t1y t1z t2x t2y t2z normal-impulse jacobian) points
      (with-box-manifold-columns ((mfirst first) (mcount count) friction-impulse-1 friction-impulse-2
                                  twist-impulse (mjacobian jacobian))
          manifolds
        (dotimes (mi (box-manifold-columns-length manifolds))
          (let ((first (aref mfirst mi)))
            (declare (type index first))
            (with-box-point-sides (v first)
              (loop for k of-type index from first below (+ first (aref mcount mi))
                    do (let ((jo (* +box-jacobian-width+ k)) (pn (aref normal-impulse k)))
                         (declare (type index jo) (type single-float pn))
                         (apply! (* pn (aref nx k)) (* pn (aref ny k)) (* pn (aref nz k))
                                 ((* pn (jac 3)) (* pn (jac 4)) (* pn (jac 5)))
                                 ((* pn (jac 9)) (* pn (jac 10)) (* pn (jac 11))))))
              (with-box-manifold-friction (mi)
                (apply! (+ (* f1 (aref t1x first)) (* f2 (aref t2x first)))
                        (+ (* f1 (aref t1y first)) (* f2 (aref t2y first)))
                        (+ (* f1 (aref t1z first)) (* f2 (aref t2z first)))
                        ((+ (* f1 (mj 6)) (* f2 (mj 9)) (* tw (mj 24)))
                         (+ (* f1 (mj 7)) (* f2 (mj 10)) (* tw (mj 25)))
                         (+ (* f1 (mj 8)) (* f2 (mj 11)) (* tw (mj 26))))
                        ((+ (* f1 (mj 18)) (* f2 (mj 21)) (* tw (mj 27)))
                         (+ (* f1 (mj 19)) (* f2 (mj 22)) (* tw (mj 28)))
                         (+ (* f1 (mj 20)) (* f2 (mj 23)) (* tw (mj 29))))))))))))
  nil)

(defmacro with-box-manifold-motion ((first) &body body)
  "Run BODY with what the points of the manifold whose first point is FIRST share in a pass: its
normal AX AY AZ, the move of its gap by the sides' deltas, DN = n . (da - db), and the sides'
turns so far, TAX TAY TAZ and TBX TBY TBZ (the dummy's zero); for every point of a manifold has
the same two sides and normal (box-points-one-manifold-p), and a pass moves neither the deltas
nor the turns. Expanded in solve-box-points inside with-box-point-columns of ROW, ROW-B, NX, NY
and NZ, over the deltas D and TURNS. #BXSOLV"
  `(let* ((p (delta-row (aref row ,first))) (pb (delta-row (aref row-b ,first)))
          (tr (* 3 (aref row ,first))) (tb (* 3 (aref row-b ,first)))
          (ax (aref nx ,first)) (ay (aref ny ,first)) (az (aref nz ,first))
          (dn (+ (* ax (- (aref d p) (aref d pb))) (* ay (- (aref d (+ p 1)) (aref d (+ pb 1))))
                 (* az (- (aref d (+ p 2)) (aref d (+ pb 2))))))
          (tax (aref turns tr)) (tay (aref turns (+ tr 1))) (taz (aref turns (+ tr 2)))
          (tbx (aref turns tb)) (tby (aref turns (+ tb 1))) (tbz (aref turns (+ tb 2))))
     (declare (type index p pb tr tb) (type single-float ax ay az dn tax tay taz tbx tby tbz))
     ,@body))
;; Box points in the substeps:8 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:9]]
(defmacro box-point-normal-pass ()
  "The normal impulse of box point K in a pass of solve-box-points: with the soft bias when
USE-BIAS, clamped to push only and to the point's cap, the speed of an impact kept; the new
impulse added to TOTAL and its lever arm times it to TWIST-LIMIT. Expanded in solve-box-points
inside with-box-point-sides and with-box-manifold-motion, whose variables it reads. #BXSOLV"
  `(let* (;; the gap now: moved by each side's delta and turn (the dummy's are zero),
          ;; n . (da - db) + ta . (ra x n) - tb . (rb x n), and by a posted box's travel
          ;; so far this step (zero for any other point)
          (s (- (+ (aref separation k) dn
                   (- (+ (* tax (jac 0)) (* tay (jac 1)) (* taz (jac 2)))
                      (+ (* tbx (jac 6)) (* tby (jac 7)) (* tbz (jac 8)))))
                (* (aref kvn k) elapsed)))
          ;; n . (va - vb) + wa . (ra x n) - wb . (rb x n), less a posted box's velocity
          ;; along the normal
          (vn (- (+ (+ (* ax (- avx bvx)) (* ay (- avy bvy)) (* az (- avz bvz)))
                    (- (+ (* awx (jac 0)) (* awy (jac 1)) (* awz (jac 2)))
                       (+ (* bwx (jac 6)) (* bwy (jac 7)) (* bwz (jac 8)))))
                 (aref kvn k)))
          (positive (> s 0.0))
          (bias (cond (positive (* s inv-h))
                      (use-bias (max (* bias-rate s) (- push-max)))
                      (t 0.0)))
          (ms (if (and use-bias (not positive)) mass-scale 1.0))
          (is (if (and use-bias (not positive)) impulse-scale 0.0))
          (old (aref normal-impulse k))
          ;; held to its cap, which only a point against a posted box has ([[#BXPUSH]])
          (new (min (aref push-cap k) (max 0.0 (- old (* ms (aref normal-mass k) (+ vn bias)) (* is old)))))
          (pn (- new old)))
     (declare (type single-float s vn bias ms is old new pn))
     ;; an impact: the first push this step of a point with restitution that approached,
     ;; before the pass, faster than the threshold; its speed is kept for the bounce
     (when (and (> (aref restitution k) 0.0) (= (aref pushed k) 0.0) (> new 0.0)
                (< (aref approach k) (- threshold)))
       (setf (aref impact-speed k)
             (box-point-impact-speed (aref approach k) s positive use-bias inv-h
                                     (* (- (if (> m 0.0) 1.0 0.0) (if (> mb 0.0) 1.0 0.0))
                                        (+ (* hgx ax) (* hgy ay) (* hgz az))))))
     (setf (aref normal-impulse k) new
           (aref pushed k) (max (aref pushed k) new)
           total (+ total new) twist-limit (+ twist-limit (* (aref lever-arm k) new))
           change (max change (abs pn)))
     (apply! (* pn ax) (* pn ay) (* pn az)
             ((* pn (jac 3)) (* pn (jac 4)) (* pn (jac 5)))
             ((* pn (jac 9)) (* pn (jac 10)) (* pn (jac 11))))))

(defmacro box-manifold-friction-pass ()
  "The twist and then the friction of manifold MI in a relax pass of solve-box-points: the twist
about the normal held within the manifold's friction times TWIST-LIMIT, its points' lever arms
times their normal impulses; the two tangent impulses at its centre, through its 2 x 2 tangent
mass, held together inside the cone of its friction times TOTAL, its points' normal impulses.
Expanded inside with-box-point-sides of its first point FIRST, whose variables it reads. #BXSOLV"
  `(with-box-manifold-friction (mi)
     (let* ((mu (aref mfriction mi))
            (n1 (aref nx first)) (n2 (aref ny first)) (n3 (aref nz first))
            ;; the first side's spin less the second's, about the normal
            (spin (+ (* n1 (- awx bwx)) (* n2 (- awy bwy)) (* n3 (- awz bwz))))
            (bound (* mu twist-limit))
            (new (max (- bound) (min bound (- tw (* (aref twist-mass mi) spin)))))
            (dt (- new tw)))
       (declare (type single-float mu n1 n2 n3 spin bound new dt))
       (setf (aref twist-impulse mi) new)
       (apply! 0.0 0.0 0.0 ((* dt (mj 24)) (* dt (mj 25)) (* dt (mj 26))) ((* dt (mj 27)) (* dt (mj 28)) (* dt (mj 29))))
       ;; the velocity at the centre along the tangents, less a posted box's
       (let* ((ux (- (- avx bvx) (aref kvx first))) (uy (- (- avy bvy) (aref kvy first))) (uz (- (- avz bvz) (aref kvz first)))
              (u1 (+ (+ (* ux (aref t1x first)) (* uy (aref t1y first)) (* uz (aref t1z first)))
                     (- (+ (* awx (mj 0)) (* awy (mj 1)) (* awz (mj 2))) (+ (* bwx (mj 12)) (* bwy (mj 13)) (* bwz (mj 14))))))
              (u2 (+ (+ (* ux (aref t2x first)) (* uy (aref t2y first)) (* uz (aref t2z first)))
                     (- (+ (* awx (mj 3)) (* awy (mj 4)) (* awz (mj 5))) (+ (* bwx (mj 15)) (* bwy (mj 16)) (* bwz (mj 17))))))
              (g1 (- f1 (+ (* (aref k11 mi) u1) (* (aref k12 mi) u2))))
              (g2 (- f2 (+ (* (aref k12 mi) u1) (* (aref k22 mi) u2))))
              (limit (* mu total))
              (len2 (+ (* g1 g1) (* g2 g2))))
         (declare (type single-float ux uy uz u1 u2 g1 g2 limit len2))
         (when (> len2 (* limit limit))
           (let ((scale (if (> len2 0.0) (/ limit (fsqrt len2)) 0.0)))
             (setf g1 (* g1 scale) g2 (* g2 scale))))
         (setf (aref friction-impulse-1 mi) g1 (aref friction-impulse-2 mi) g2)
         (let ((d1 (- g1 f1)) (d2 (- g2 f2)))
           (declare (type single-float d1 d2))
           (apply! (+ (* d1 (aref t1x first)) (* d2 (aref t2x first)))
                   (+ (* d1 (aref t1y first)) (* d2 (aref t2y first)))
                   (+ (* d1 (aref t1z first)) (* d2 (aref t2z first)))
                   ((+ (* d1 (mj 6)) (* d2 (mj 9))) (+ (* d1 (mj 7)) (* d2 (mj 10))) (+ (* d1 (mj 8)) (* d2 (mj 11))))
                   ((+ (* d1 (mj 18)) (* d2 (mj 21))) (+ (* d1 (mj 19)) (* d2 (mj 22)))
                    (+ (* d1 (mj 20)) (* d2 (mj 23))))))))))
;; Box points in the substeps:9 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:10]]
(defconstant +box-normal-sweeps+ 4
  "The most sweeps a pass makes over a box manifold's normal impulses. #BXSOLV")

(defconstant +box-sweep-share+ 0.05
  "The share of a box manifold's total normal impulse by which some point's must have changed in
a sweep for the pass to sweep its normals again. #BXSOLV")

(defun solve-box-points (set v d inv-h use-bias)
  "One pass over the box manifolds: each point's normal impulse, with the soft bias when USE-BIAS
(the solve) and without it (the relax), clamped to push only, keeping the speed of an impact;
then, in the relax alone, the manifold's twist and its friction at its centre, held in the
cone. #BXSOLV"
  (declare (type box-set set) (type f32-column v d) (type single-float inv-h) #.+kernel-policy+)
  (let ((points (box-set-points set)) (manifolds (box-set-manifolds set)) (turns (box-set-turns set))
        (bias-rate (box-set-bias-rate set)) (mass-scale (box-set-mass-scale set))
        (impulse-scale (box-set-impulse-scale set)) (push-max (box-set-push-max set))
        (threshold (box-set-threshold set)) (elapsed (box-set-elapsed set))
        (hgx (box-set-hgx set)) (hgy (box-set-hgy set)) (hgz (box-set-hgz set))
        (table (box-set-inertias set)) (dummy (box-set-dummy set)))
    (declare (type f32-column turns table) (type index dummy)
             (type single-float bias-rate mass-scale impulse-scale push-max threshold elapsed hgx hgy hgz))
    (with-box-point-columns (row row-b kvx kvy kvz nx ny nz t1x t1y t1z t2x t2y t2z separation normal-mass
                             normal-impulse restitution pushed impact-speed approach jacobian kvn push-cap lever-arm
                             rx ry rz sx sy sz)
        points
      ;; the normal velocity of each point that may strike, before this pass pushes any point:
      ;; the corners of a box landing flat all strike at the speed the first one does
      (when (box-set-bouncy set)
        (dotimes (k (box-point-columns-length points))
          (when (and (> (aref restitution k) 0.0) (= (aref pushed k) 0.0))
            (with-box-point (v k)
              (setf (aref approach k)
                    (multiple-value-bind (ux uy uz) (point-velocity)
                      (+ (* ux (aref nx k)) (* uy (aref ny k)) (* uz (aref nz k)))))))))
      (with-box-manifold-columns ((mfirst first) (mcount count) (mfriction friction) k11 k12 k22 twist-mass
                                  friction-impulse-1 friction-impulse-2 twist-impulse (mjacobian jacobian))
          manifolds
        (dotimes (mi (box-manifold-columns-length manifolds))
          (let ((first (aref mfirst mi)) (total 0.0) (twist-limit 0.0) (change 0.0))
            (declare (type index first) (type single-float total twist-limit change))
            (with-box-point-sides (v first)
              (with-box-manifold-motion (first)
                (loop for sweep of-type fixnum from 1
                      do (setf total 0.0 twist-limit 0.0 change 0.0)
                         (loop for k of-type index from first below (+ first (aref mcount mi))
                               do (let ((jo (* +box-jacobian-width+ k)))
                                    (declare (type index jo))
                                    (box-point-normal-pass)))
                      ;; again while a sweep still moved some point's impulse by a share of the total
                      while (and (< sweep +box-normal-sweeps+) (> change (* +box-sweep-share+ total)))))
              ;; friction in the relax alone, as Box3D's solver gives it
              (unless use-bias (box-manifold-friction-pass))))))))
  nil)
;; Box points in the substeps:10 ends here

;; [[file:../physics.org::#BXSOLV][Box points in the substeps:11]]
(defun turn-box-orientations (world)
  "When WORLD's box set solved points this step, set each awake box's orientation to the one it
had at the step's start turned by the sum of its substeps' turns, in place of the turn by its
last spin over the step. #BXSOLV"
  (let ((set (physics-world-box-bodies world)))
    (declare (type box-set set) #.+kernel-policy+)
    (when (box-set-solving set)
      (let ((start-q (box-set-start-q set)) (turns (box-set-turns set)) (rows (box-set-rows set)))
        (declare (type f32-column start-q turns) (type fixnum-column rows))
        (with-body-columns (qw qx qy qz) (physics-world-awake world)
          (dotimes (j (box-set-row-count set))
            (let* ((i (aref rows j)) (tr (* 3 i)) (o (* 4 j))
                   ;; half the turn, and the orientation at the step's start: q + (0, t/2) q
                   (ax (* 0.5 (aref turns tr))) (ay (* 0.5 (aref turns (+ tr 1)))) (az (* 0.5 (aref turns (+ tr 2))))
                   (w0 (aref start-q o)) (x0 (aref start-q (+ o 1))) (y0 (aref start-q (+ o 2))) (z0 (aref start-q (+ o 3)))
                   (nw (- w0 (+ (* ax x0) (* ay y0) (* az z0))))
                   (nx (+ x0 (+ (* ax w0) (- (* ay z0) (* az y0)))))
                   (ny (+ y0 (+ (* ay w0) (- (* az x0) (* ax z0)))))
                   (nz (+ z0 (+ (* az w0) (- (* ax y0) (* ay x0)))))
                   (s (/ 1.0 (fsqrt (+ (* nw nw) (* nx nx) (* ny ny) (* nz nz))))))
              (declare (type index i tr o) (type single-float ax ay az w0 x0 y0 z0 nw nx ny nz s))
              (setf (aref qw i) (* nw s) (aref qx i) (* nx s) (aref qy i) (* ny s) (aref qz i) (* nz s))))))))
  nil)

(defconstant +box-bounce-passes+ 4
  "The passes of the bounce over the box points that struck in a step. #BXSOLV")

(declaim (inline bounce-impulse))
(defun bounce-impulse (old normal-mass restitution impact-speed dv vn)
  "The bounce a point that struck at IMPACT-SPEED carries after a pass, from OLD before it: what
makes its normal velocity VN the RESTITUTION times that speed, less half the change DV gravity
gives it over a substep, through its NORMAL-MASS; a push, never a pull. #BXSOLV"
  (declare (type single-float old normal-mass restitution impact-speed dv vn))
  (max 0.0 (+ old (* normal-mass (- (- (* restitution impact-speed) (* 0.5 dv)) vn)))))

(defun bounce-box-points (set v)
  "After the substeps, give each box point that struck this step the push that makes it leave
at its restitution times the speed it struck at, in +box-bounce-passes+ Gauss-Seidel passes, each
point's bounce a push of its own, never a pull. The speed is the instant's at the step's end,
which the velocity of the substep to come reaches less half that substep's gravity. #BXSOLV"
  (declare (type box-set set) (type f32-column v) #.+kernel-policy+)
  (let ((points (box-set-points set))
        (hgx (box-set-hgx set)) (hgy (box-set-hgy set)) (hgz (box-set-hgz set))
        (table (box-set-inertias set)) (dummy (box-set-dummy set)))
    (declare (type single-float hgx hgy hgz) (type f32-column table) (type index dummy))
    (with-box-point-columns (row row-b kvx kvy kvz nx ny nz rx ry rz sx sy sz normal-mass
                             restitution impact-speed bounce)
        points
      (dotimes (pass +box-bounce-passes+)
        (dotimes (k (box-point-columns-length points))
          (when (> (aref impact-speed k) 0.0)
            (with-box-point (v k)
              (let* ((ax (aref nx k)) (ay (aref ny k)) (az (aref nz k))
                     (vn (multiple-value-bind (ux uy uz) (point-velocity) (+ (* ux ax) (* uy ay) (* uz az))))
                     ;; the change of vn over a substep under gravity
                     (dv (* (- (if (> m 0.0) 1.0 0.0) (if (> mb 0.0) 1.0 0.0))
                            (+ (* hgx ax) (* hgy ay) (* hgz az))))
                     (old (aref bounce k))
                     (new (bounce-impulse old (aref normal-mass k) (aref restitution k) (aref impact-speed k)
                                          dv vn))
                     (push (- new old)))
                (declare (type single-float ax ay az vn dv old new push))
                (setf (aref bounce k) new)
                (push! (* push ax) (* push ay) (* push az)))))))))
  nil)

(defun turn-box-rows (set v h)
  "Add to each awake box's turn its spin over the substep H, after the positions integrate. #BXSOLV"
  (declare (type box-set set) (type f32-column v) (type single-float h) #.+kernel-policy+)
  (let ((rows (box-set-rows set)) (turns (box-set-turns set)))
    (declare (type fixnum-column rows) (type f32-column turns))
    (dotimes (j (box-set-row-count set))
      (let* ((i (aref rows j)) (o (solver-row i)) (tr (* 3 i)))
        (declare (type index i o tr))
        (setf (aref turns tr) (+ (aref turns tr) (* h (aref v (+ o 3))))
              (aref turns (+ tr 1)) (+ (aref turns (+ tr 1)) (* h (aref v (+ o 4))))
              (aref turns (+ tr 2)) (+ (aref turns (+ tr 2)) (* h (aref v (+ o 5))))))))
  nil)
;; Box points in the substeps:11 ends here

;; [[file:../physics.org::#BXBRAC][Box points on a braced body:1]]
(declaim (inline brace-still-row))
(defun brace-still-row (braced flags v row still2 bit)
  "Mark the awake ROW with BIT in BRACED when its solver velocity in V is still (STILL2, the sleep
speed squared), and, for +brace-braced+, braced in its FLAGS. #BXBRAC"
  (declare (type fixnum-column braced flags) (type f32-column v) (type index row) (type fixnum bit)
           (type single-float still2))
  (when (or (minusp still2) (still-row-p v (solver-row row) still2))
    (setf (aref braced row) (logior (aref braced row) bit))
    (when (= bit +brace-braced+)
      (setf (aref flags row) (logior (aref flags row) +flag-braced+)))))

(declaim (inline pressed-still-p))
(defun pressed-still-p (v row sign nx ny nz still2)
  "Whether the awake ROW's solver velocity in V, less its part into a support whose normal out of
the support is SIGN times NX NY NZ, is slower than the sleep speed (STILL2, its square). #BXBRAC"
  (declare (type f32-column v) (type index row) (type single-float sign nx ny nz still2))
  (let* ((o (solver-row row))
         (vx (aref v o)) (vy (aref v (+ o 1))) (vz (aref v (+ o 2)))
         (out (* sign (+ (* vx nx) (* vy ny) (* vz nz))))
         (into (min out 0.0)))
    (declare (type index o) (type single-float vx vy vz out into))
    (< (- (+ (* vx vx) (* vy vy) (* vz vz)) (* into into)) still2)))

(defun note-box-supports (points braced flags v n still2 up-x up-y up-z)
  "The box points' supports: brace each still awake row of the N held by one of POINTS that
carried load from something static (the dummy row N on its other side); then mark, with
+brace-support+, each still awake row resting within 25 degrees of the vertical (UP-X UP-Y UP-Z
against gravity) on a braced awake row through a point that carried load, and fold those marks
into braced ones. #BXBRAC"
  (declare (type box-point-columns points) (type fixnum-column braced flags) (type f32-column v)
           (type index n) (type single-float still2 up-x up-y up-z) #.+kernel-policy+)
  (with-box-point-columns (row row-b nx ny nz normal-impulse) points
    (let ((m (box-point-columns-length points)))
      (dotimes (k m)
        (let ((a (aref row k)) (b (aref row-b k)))
          (declare (type index a b))
          (when (and (> (aref normal-impulse k) 0.0) (not (eq (< a n) (< b n)))
                     ;; the awake side's velocity but for its part into the support: the normal
                     ;; pushes the first side, so it points out of the support for the first
                     (pressed-still-p v (min a b) (if (< a n) 1.0 -1.0) (aref nx k) (aref ny k) (aref nz k) still2))
            (brace-still-row braced flags v (min a b) -1.0 +brace-braced+))))
      ;; the normal pushes the first side off the second: rise is the first side's height over it
      (dotimes (k m)
        (let ((a (aref row k)) (b (aref row-b k))
              (rise (upward-part (aref nx k) (aref ny k) (aref nz k) up-x up-y up-z)))
          (declare (type index a b) (type single-float rise))
          (when (and (> (aref normal-impulse k) 0.0) (< a n) (< b n))
            (cond ((and (> rise 0.9) (logtest (aref braced b) +brace-braced+)
                        (pressed-still-p v a 1.0 (aref nx k) (aref ny k) (aref nz k) still2))
                   (brace-still-row braced flags v a -1.0 +brace-support+))
                  ((and (< rise -0.9) (logtest (aref braced a) +brace-braced+)
                        (pressed-still-p v b -1.0 (aref nx k) (aref ny k) (aref nz k) still2))
                   (brace-still-row braced flags v b -1.0 +brace-support+)))))))
    (dotimes (i n)
      (when (logtest (aref braced i) +brace-support+)
        (setf (aref braced i) (logior (logandc2 (aref braced i) +brace-support+) +brace-braced+)
              (aref flags i) (logior (aref flags i) +flag-braced+))))))

(defun brace-box-point-sides (points braced inverse-mass brace-ratio v n up-x up-y up-z)
  "Give each of POINTS between two awake rows of the N, one of which rests on the other as on
something static (rests-static-p), the dummy row N on that side, and zero the static side's
solver velocity and spin in V. #BXBRAC"
  (declare (type box-point-columns points) (type fixnum-column braced) (type f32-column inverse-mass v)
           (type index n) (type single-float brace-ratio up-x up-y up-z) #.+kernel-policy+)
  (with-box-point-columns (row row-b nx ny nz) points
    (dotimes (k (box-point-columns-length points))
      (let ((a (aref row k)) (b (aref row-b k)))
        (declare (type index a b))
        (when (and (< a n) (< b n))
          (let ((rise (upward-part (aref nx k) (aref ny k) (aref nz k) up-x up-y up-z)))
            (declare (type single-float rise))
            (flet ((still (side)
                     (declare (type index side))
                     (let ((o (solver-row side))) (fill v 0.0 :start o :end (+ o 6)))))
              (cond ((rests-static-p braced inverse-mass brace-ratio b a rise)
                     (setf (aref row-b k) n)
                     (still b))
                    ((rests-static-p braced inverse-mass brace-ratio a b (- rise))
                     (setf (aref row k) n)
                     (still a))))))))))

(defun brace-box-points (world set)
  "The bracing of SET's points, this step's, in WORLD ([[#BXBRAC]]): when the contacts' bracing
pass ran this step, mark the bodies the points brace (note-box-supports), then make one-sided
each point on which a much heavier body rests on a braced one (brace-box-point-sides). #BXBRAC"
  (declare (type box-set set) #.+kernel-policy+)
  (when (= (physics-world-braced-step world) (physics-world-step-count world))
    (let* ((awake (physics-world-awake world))
           (n (body-columns-length awake))
           (points (box-set-points set))
           (v (physics-world-velocities world))
           (braced (physics-world-braced world))
           (g (fsqrt (+ (expt (physics-world-gravity-x world) 2) (expt (physics-world-gravity-y world) 2)
                        (expt (physics-world-gravity-z world) 2))))
           (up-x (/ (- (physics-world-gravity-x world)) g))
           (up-y (/ (- (physics-world-gravity-y world)) g))
           (up-z (/ (- (physics-world-gravity-z world)) g)))
      (declare (type index n) (type f32-column v) (type fixnum-column braced) (type single-float g up-x up-y up-z))
      (with-world-parameters ((brace-ratio brace-mass-ratio)) world
        (note-box-supports points braced (body-columns-flags awake) v n
                           (f32 (expt (physics-world-sleep-speed world) 2)) up-x up-y up-z)
        (brace-box-point-sides points braced (body-columns-inverse-mass awake) brace-ratio v n
                               up-x up-y up-z))))
  set)
;; Box points on a braced body:1 ends here

;; [[file:../physics.org::#BXSPHR][A box against a sphere:1]]
(declaim (inline box-sphere-key))
(defun box-sphere-key (slot sphere-slot)
  "The key of the point between the box in handle slot SLOT and the sphere in handle slot
SPHERE-SLOT: a box-box key's bit with the low byte all ones, which no box-box key has. #BXSPHR"
  (declare (type (unsigned-byte 24) slot sphere-slot))
  (logior (ash slot 34) (ash 1 32) (ash sphere-slot 8) 255))

(defun box-sphere-point (set owner key row-a row-b reach ax ay az radius
                         bcx bcy bcz qw qx qy qz hx hy hz)
  "Append to SET, as a point found by the box OWNER under KEY, the point between the sphere of
centre AX AY AZ and RADIUS at solver row ROW-A and the box of centre BCX BCY BCZ, orientation QW ..
QZ and half-extents HX HY HZ at solver row ROW-B, when its gap is under REACH: the box's point
nearest the centre, the normal from the box to the sphere. #BXSPHR"
  (declare (type box-set set) (type fixnum owner key) (type index row-a row-b)
           (type single-float reach ax ay az radius bcx bcy bcz qw qx qy qz hx hy hz) #.+kernel-policy+)
  (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33) (box-axes qw qx qy qz)
    (declare (type single-float r11 r12 r13 r21 r22 r23 r31 r32 r33))
    (let* ((dx (- ax bcx)) (dy (- ay bcy)) (dz (- az bcz))
           ;; the centre in the box's frame, and its nearest point of the box
           (u (+ (* r11 dx) (* r21 dy) (* r31 dz)))
           (v (+ (* r12 dx) (* r22 dy) (* r32 dz)))
           (w (+ (* r13 dx) (* r23 dy) (* r33 dz)))
           (cu (max (- hx) (min hx u))) (cv (max (- hy) (min hy v))) (cw (max (- hz) (min hz w)))
           (lu (- u cu)) (lv (- v cv)) (lw (- w cw))
           (d2 (+ (* lu lu) (* lv lv) (* lw lw))))
      (declare (type single-float dx dy dz u v w cu cv cw lu lv lw d2))
      (multiple-value-bind (nu nv nw gap)
          (if (> d2 0.0)
              ;; outside: along the way from the nearest point to the centre
              (let* ((dist (fsqrt d2)) (inv (/ 1.0 dist)))
                (values (* lu inv) (* lv inv) (* lw inv) (- dist radius)))
              ;; inside: out of the face it is least deep behind, onto which the point moves
              (let ((du (- hx (abs u))) (dv (- hy (abs v))) (dw (- hz (abs w))))
                (cond ((and (<= du dv) (<= du dw))
                       (setf cu (if (>= u 0.0) hx (- hx)))
                       (values (if (>= u 0.0) 1.0 -1.0) 0.0 0.0 (- (- du) radius)))
                      ((<= dv dw)
                       (setf cv (if (>= v 0.0) hy (- hy)))
                       (values 0.0 (if (>= v 0.0) 1.0 -1.0) 0.0 (- (- dv) radius)))
                      (t
                       (setf cw (if (>= w 0.0) hz (- hz)))
                       (values 0.0 0.0 (if (>= w 0.0) 1.0 -1.0) (- (- dw) radius))))))
        (declare (type single-float nu nv nw gap))
        (when (< gap reach)
          (let ((nx (+ (* r11 nu) (* r12 nv) (* r13 nw)))
                (ny (+ (* r21 nu) (* r22 nv) (* r23 nw)))
                (nz (+ (* r31 nu) (* r32 nv) (* r33 nw))))
            (declare (type single-float nx ny nz))
            (add-box-point set row-a owner key nx ny nz (* (- radius) nx) (* (- radius) ny) (* (- radius) nz) gap
                           row-b
                           (+ (* r11 cu) (* r12 cv) (* r13 cw))
                           (+ (* r21 cu) (* r22 cv) (* r23 cw))
                           (+ (* r31 cu) (* r32 cv) (* r33 cw))))))))
  set)

(declaim (inline sphere-meets-box-p))
(defun sphere-meets-box-p (filtering sphere-flags box-flags)
  "True when a row of SPHERE-FLAGS is a sphere that meets bodies and meets, by the filters when
FILTERING, a box of BOX-FLAGS. #BXSPHR"
  (declare (type fixnum sphere-flags box-flags))
  (and (not (logtest sphere-flags (logior +flag-box-shape+ +flag-terrain-only+)))
       (rows-meet-p filtering sphere-flags box-flags)))

(defconstant +box-sphere-span+ 8
  "The most cells each way a box walks in the grid of the awake spheres, or in the sleeping grids,
to find the spheres it may meet; a reach spanning more visits every row instead. #BXSPHR")

(defun grid-awake-spheres (world set n dt gstep)
  "Bucket the awake spheres among the first N awake rows of WORLD that meet bodies into SET's grid
of spheres, whose items are their rows, in cells of the largest diameter and the margin, and keep
the largest travel among them in a step of DT seconds in which gravity adds GSTEP. #BXSPHR"
  (declare (type box-set set) (type index n) (type single-float dt gstep) #.+kernel-policy+)
  (let ((awake (physics-world-awake world)) (count 0) (travel 0.0))
    (declare (type index count) (type single-float travel))
    (when (< (length (box-set-sphere-rows set)) n)
      (let ((m (max n (* 2 (length (box-set-sphere-rows set))))))
        (setf (box-set-sphere-rows set) (make-array m :element-type 'fixnum :initial-element 0)
              (box-set-sx set) (make-array m :element-type 'single-float :initial-element 0.0)
              (box-set-sy set) (make-array m :element-type 'single-float :initial-element 0.0)
              (box-set-sz set) (make-array m :element-type 'single-float :initial-element 0.0)
              (box-set-found set) (make-array m :element-type 'fixnum :initial-element 0))
        (hash-grid-reserve (box-set-spheres set) m)))
    (let ((rows (box-set-sphere-rows set)) (sx (box-set-sx set)) (sy (box-set-sy set)) (sz (box-set-sz set)))
      (with-body-columns (x y z vx vy vz flags) awake
        (dotimes (i n)
          (unless (logtest (aref flags i) (logior +flag-box-shape+ +flag-terrain-only+))
            (setf (aref rows count) i (aref sx count) (aref x i) (aref sy count) (aref y i) (aref sz count) (aref z i)
                  travel (max travel (step-travel (aref vx i) (aref vy i) (aref vz i) dt gstep)))
            (incf count))))
      (build-hash-grid (box-set-spheres set)
                       (+ (* 2.0 (f32 (physics-world-max-radius world))) (f32 (physics-world-margin world)))
                       count sx sy sz rows))
    (setf (box-set-sphere-travel set) travel)
    set))

(defun near-sphere-rows (set x y z far)
  "Write into SET's room for found rows, in increasing order, the rows of the awake spheres in
SET's grid of spheres whose cells lie within FAR of the point X Y Z, and return their count; or
return -1, writing nothing, when FAR spans more than +box-sphere-span+ cells. #BXSPHR"
  (declare (type box-set set) (type single-float x y z far) #.+kernel-policy+)
  (let* ((grid (box-set-spheres set)) (found (box-set-found set)) (count 0)
         (cells (* far (hash-grid-inv-cell grid))))
    (declare (type fixnum count) (type single-float cells))
    (cond
      ((zerop (hash-grid-count grid)) 0)
      ((> cells (float +box-sphere-span+ 1.0)) -1)
      (t
       (do-grid-neighbours (j grid x y z :span (ceiling cells))
         (setf (aref found count) j)
         (incf count))
       ;; the rows in increasing order, as a walk over every row meets them
       (loop for i of-type fixnum from 1 below count
             do (let ((v (aref found i)) (k i))
                  (declare (type fixnum v k))
                  (loop while (and (> k 0) (> (aref found (1- k)) v))
                        do (setf (aref found k) (aref found (1- k)))
                           (decf k))
                  (setf (aref found k) v)))
       count))))

(defun find-box-sphere-points (world set row reach dt gstep)
  "Append to SET's points those between the awake box at ROW of WORLD and every sphere near it,
awake (found in SET's grid of spheres) or, held still, sleeping (found in the sleeping grids),
each in the order of its rows; REACH is the box's, grown to the travel of an awake sphere
relative to it in a step of DT seconds in which gravity adds GSTEP. #BXSPHR"
  (declare (type box-set set) (type index row) (type single-float reach dt gstep) #.+kernel-policy+)
  (let* ((awake (physics-world-awake world)) (sleeping (physics-world-sleeping world))
         (ids (physics-world-ids world))
         (n (body-columns-length awake)) (filtering (physics-world-filtering world))
         (rmax (f32 (physics-world-max-radius world))))
    (declare (type index n) (type single-float rmax))
    (with-body-columns (x y z vx vy vz qw qx qy qz radius handle flags) awake
      (let* ((owner (aref handle row)) (slot (handle-index owner)) (box-flags (aref flags row))
             (cx (aref x row)) (cy (aref y row)) (cz (aref z row)) (r (aref radius row))
             (hx (aref (box-set-hx set) slot)) (hy (aref (box-set-hy set) slot)) (hz (aref (box-set-hz set) slot))
             (travel (step-travel (aref vx row) (aref vy row) (aref vz row) dt 0.0))
             ;; the farthest centre an awake sphere may meet this box from, with a millimetre
             ;; for the rounding of the travels
             (far (+ r rmax (max reach (+ travel (box-set-sphere-travel set))) 1e-3))
             (sleep-far (+ r rmax reach 1e-3))
             (sleep-cells (/ sleep-far (the single-float (f32 (grid-cell-size world))))))
        (declare (type fixnum owner box-flags) (type single-float cx cy cz r hx hy hz travel far sleep-far sleep-cells))
        (flet ((meet (buffer j row-j reach)
                 ;; the sphere at row J of BUFFER, at solver row ROW-J
                 (declare (type body-columns buffer) (type index j row-j) (type single-float reach))
                 (with-body-columns ((sx x) (sy y) (sz z) (sr radius) (sh handle) (sf flags)) buffer
                   (when (sphere-meets-box-p filtering (aref sf j) box-flags)
                     (let* ((dx (- (aref sx j) cx)) (dy (- (aref sy j) cy)) (dz (- (aref sz j) cz))
                            (near (+ r (aref sr j) reach)))
                       (when (< (+ (* dx dx) (* dy dy) (* dz dz)) (* near near))
                         (box-sphere-point set owner (box-sphere-key slot (handle-index (aref sh j))) row-j row reach
                                           (aref sx j) (aref sy j) (aref sz j) (aref sr j)
                                           cx cy cz (aref qw row) (aref qx row) (aref qy row) (aref qz row)
                                           hx hy hz)))))))
          (flet ((meet-awake (j)
                   (declare (type index j))
                   (meet awake j j (max reach (step-travel (- (aref vx j) (aref vx row)) (- (aref vy j) (aref vy row))
                                                           (- (aref vz j) (aref vz row)) dt gstep)))))
            (let ((count (near-sphere-rows set cx cy cz far)) (found (box-set-found set)))
              (declare (type fixnum count) (type fixnum-column found))
              (if (minusp count)
                  (dotimes (j n) (meet-awake j))
                  (dotimes (k count) (meet-awake (aref found k))))))
          (let ((m (body-columns-length sleeping)))
            (cond ((zerop m))
                  ((> sleep-cells (float +box-sphere-span+ 1.0))
                   (dotimes (j m) (meet sleeping j n reach)))
                  (t
                   (do-sleepers-in-row-order (h world cx cy cz :span (ceiling sleep-cells))
                       (let ((s (handle-index h)))
                         (and (= (aref (handle-table-set ids) s) +set-sleeping+)
                              (= (aref (handle-table-generation ids) s) (handle-generation h))
                              (not (logtest (aref (body-columns-flags sleeping) (aref (handle-table-local ids) s))
                                            +flag-box-shape+))))
                     (meet sleeping (aref (handle-table-local ids) (handle-index h)) n reach)))))))))
  set)

(defun sleeping-box-sphere-points (world set b margin dt gstep)
  "Append to SET's points those between the sleeping box at row B of WORLD's sleeping buffer, held
still, and every awake sphere near it (found in SET's grid of spheres, in the order of its rows),
within MARGIN or the sphere's travel in a step of DT seconds in which gravity adds GSTEP. #BXSPHR"
  (declare (type box-set set) (type index b) (type single-float margin dt gstep) #.+kernel-policy+)
  (let* ((awake (physics-world-awake world)) (sleeping (physics-world-sleeping world))
         (n (body-columns-length awake)) (filtering (physics-world-filtering world))
         (found (box-set-found set)) (rmax (f32 (physics-world-max-radius world))))
    (declare (type index n) (type fixnum-column found) (type single-float rmax))
    (with-body-columns ((bx x) (by y) (bz z) (bqw qw) (bqx qx) (bqy qy) (bqz qz) (br radius) (bh handle) (bf flags))
        sleeping
      (with-body-columns (x y z vx vy vz radius handle flags) awake
        (let* ((slot (handle-index (aref bh b)))
               (count (near-sphere-rows set (aref bx b) (aref by b) (aref bz b)
                                        (+ (aref br b) rmax (max margin (box-set-sphere-travel set)) 1e-3))))
          (declare (type fixnum count))
          (flet ((meet (j)
                   (declare (type index j))
                   (when (sphere-meets-box-p filtering (aref flags j) (aref bf b))
                     (let* ((reach (max margin (step-travel (aref vx j) (aref vy j) (aref vz j) dt gstep)))
                            (dx (- (aref x j) (aref bx b))) (dy (- (aref y j) (aref by b))) (dz (- (aref z j) (aref bz b)))
                            (near (+ (aref br b) (aref radius j) reach)))
                       (when (< (+ (* dx dx) (* dy dy) (* dz dz)) (* near near))
                         (box-sphere-point set (aref bh b) (box-sphere-key slot (handle-index (aref handle j))) j n reach
                                           (aref x j) (aref y j) (aref z j) (aref radius j)
                                           (aref bx b) (aref by b) (aref bz b) (aref bqw b) (aref bqx b) (aref bqy b)
                                           (aref bqz b) (aref (box-set-hx set) slot) (aref (box-set-hy set) slot)
                                           (aref (box-set-hz set) slot)))))))
            (if (minusp count)
                (dotimes (j n) (meet j))
                (dotimes (k count) (meet (aref found k)))))))))
  set)

(defun find-sleeping-box-sphere-points (world set margin dt gstep)
  "Append to SET's points those between each sleeping box of WORLD, held still, and every awake
sphere near it (sleeping-box-sphere-points); each such box's slot gets the first and the count of
its points. #BXSPHR"
  (declare (type box-set set) (type single-float margin dt gstep) #.+kernel-policy+)
  (let ((sleeping (physics-world-sleeping world)) (points (box-set-points set)))
    (with-body-columns ((bh handle) (bf flags)) sleeping
      (dotimes (b (body-columns-length sleeping))
        (when (logtest (aref bf b) +flag-box-shape+)
          (let ((slot (handle-index (aref bh b))) (start (box-point-columns-length points)))
            (sleeping-box-sphere-points world set b margin dt gstep)
            (setf (aref (box-set-first set) slot) start
                  (aref (box-set-count set) slot) (- (box-point-columns-length points) start)))))))
  set)
;; A box against a sphere:1 ends here

;; [[file:../physics.org::#BXSWEP][Fast boxes sweep their corners through the cells:1]]
(declaim (inline first-crossing))
(defun first-crossing (p i u)
  "The distance, along a unit direction whose component along an axis is U, to the first cell
face across that axis from coordinate P in cell I. #BXSWEP"
  (declare (type single-float p u) (type fixnum i))
  (cond ((> u 0.0) (/ (- (float (1+ i) 1.0) p) u))
        ((< u 0.0) (/ (- (float i 1.0) p) u))
        (t most-positive-single-float)))

(defun corner-first-solid (probe px py pz ux uy uz reach)
  "Walk the cells a point at PX PY PZ crosses along the unit direction UX UY UZ, within REACH and
at most 64 cells, and return the first solid cell it enters, the axis (0 to 2) it entered it
across and the step (+1 or -1) along that axis, as five values; the axis is -1 when it enters
none, or starts in one. #BXSWEP"
  (declare (type terrain-probe probe) (type single-float px py pz ux uy uz reach) #.+kernel-policy+)
  (let* ((ix (cell-floor px)) (iy (cell-floor py)) (iz (cell-floor pz))
         (sx (if (> ux 0.0) 1 -1)) (sy (if (> uy 0.0) 1 -1)) (sz (if (> uz 0.0) 1 -1))
         (tx (first-crossing px ix ux)) (ty (first-crossing py iy uy)) (tz (first-crossing pz iz uz))
         (ex (if (= ux 0.0) most-positive-single-float (/ 1.0 (abs ux))))
         (ey (if (= uy 0.0) most-positive-single-float (/ 1.0 (abs uy))))
         (ez (if (= uz 0.0) most-positive-single-float (/ 1.0 (abs uz)))))
    (declare (type fixnum ix iy iz sx sy sz) (type single-float tx ty tz ex ey ez))
    (unless (probe-solid-p probe ix iy iz)
      (loop repeat 64 do
        (let ((axis (cond ((and (<= tx ty) (<= tx tz)) 0) ((<= ty tz) 1) (t 2))))
          (declare (type (integer 0 2) axis))
          (when (> (case axis (0 tx) (1 ty) (t tz)) reach) (return))
          (case axis
            (0 (incf ix sx) (setf tx (+ tx ex)))
            (1 (incf iy sy) (setf ty (+ ty ey)))
            (t (incf iz sz) (setf tz (+ tz ez))))
          (when (probe-solid-p probe ix iy iz)
            (return-from corner-first-solid (values ix iy iz axis (case axis (0 sx) (1 sy) (t sz))))))))
    (values ix iy iz -1 0)))

(defun add-corner-face-point (set probe row h slot corner px py pz rx ry rz ix iy iz axis step)
  "Append to SET the point of the awake box at ROW (handle H, slot SLOT) whose CORNER, at PX PY PZ
and RX RY RZ from the centre, enters the solid cell IX IY IZ across AXIS by STEP, when that face
lies beyond the faces of the corner's own cell's neighbours and the box's centre is on its air
side: the face's normal out of the entered cell, and the corner's gap to its plane. #BXSWEP"
  (declare (type box-set set) (type terrain-probe probe) (type index row slot) (type fixnum h corner ix iy iz step)
           (type (integer 0 2) axis) (type single-float px py pz rx ry rz) #.+kernel-policy+)
  (let* ((face (+ (* 2 axis) (if (> step 0) 1 0)))
         ;; the normal out of the entered cell, back along the axis
         (nx (if (= axis 0) (float (- step) 1.0) 0.0))
         (ny (if (= axis 1) (float (- step) 1.0) 0.0))
         (nz (if (= axis 2) (float (- step) 1.0) 0.0))
         ;; the face's plane, and the corner's distance to it
         (gap (case axis
                (0 (if (> step 0) (- (float ix 1.0) px) (- px (float (1+ ix) 1.0))))
                (1 (if (> step 0) (- (float iy 1.0) py) (- py (float (1+ iy) 1.0))))
                (t (if (> step 0) (- (float iz 1.0) pz) (- pz (float (1+ iz) 1.0))))))
         ;; the neighbour of the corner's own cell across the same face
         (cx (+ (cell-floor px) (if (= axis 0) step 0)))
         (cy (+ (cell-floor py) (if (= axis 1) step 0)))
         (cz (+ (cell-floor pz) (if (= axis 2) step 0))))
    (declare (type fixnum face cx cy cz) (type single-float nx ny nz gap))
    (when (and (not (probe-solid-p probe cx cy cz))
               (< (+ (* nx rx) (* ny ry) (* nz rz)) 0.0))
      (add-box-point set row h (box-corner-key slot corner face) nx ny nz rx ry rz gap))))

(defun sweep-box-corners (world set row reach)
  "Append to SET's points, for the awake box at ROW of WORLD, each corner's first cell face
along the box's travel this step within REACH that lies beyond the faces of the corner's own
cell's neighbours ([[#BXCELL]]): the corner walks the cells it crosses (corner-first-solid), and
the face it enters a solid cell through, with the box's centre on its air side, is its point
(add-corner-face-point). #BXSWEP"
  (declare (type box-set set) (type index row) (type single-float reach) #.+kernel-policy+)
  (let ((terrain (physics-world-terrain world)) (probe (physics-world-probe world))
        (dt (physics-world-current-dt world)))
    (declare (type single-float dt))
    (when terrain
      (with-body-columns (x y z vx vy vz qw qx qy qz handle) (physics-world-awake world)
        (let* ((h (aref handle row)) (slot (handle-index h))
               (hx (aref (box-set-hx set) slot)) (hy (aref (box-set-hy set) slot)) (hz (aref (box-set-hz set) slot))
               ;; the way the box travels this step: its velocity with the step's gravity added
               (dx (+ (aref vx row) (* dt (f32 (physics-world-gravity-x world)))))
               (dy (+ (aref vy row) (* dt (f32 (physics-world-gravity-y world)))))
               (dz (+ (aref vz row) (* dt (f32 (physics-world-gravity-z world)))))
               (len (fsqrt (+ (* dx dx) (* dy dy) (* dz dz)))))
          (declare (type single-float hx hy hz dx dy dz len))
          (when (> len 0.0)
            (let ((ux (/ dx len)) (uy (/ dy len)) (uz (/ dz len)))
              (declare (type single-float ux uy uz))
              (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33)
                  (box-axes (aref qw row) (aref qx row) (aref qy row) (aref qz row))
                (declare (type single-float r11 r12 r13 r21 r22 r23 r31 r32 r33))
                (dotimes (corner 8)
                  (let* ((a (if (logbitp 0 corner) hx (- hx))) (b (if (logbitp 1 corner) hy (- hy)))
                         (c (if (logbitp 2 corner) hz (- hz)))
                         (rx (+ (* r11 a) (* r12 b) (* r13 c))) (ry (+ (* r21 a) (* r22 b) (* r23 c)))
                         (rz (+ (* r31 a) (* r32 b) (* r33 c)))
                         (px (+ (aref x row) rx)) (py (+ (aref y row) ry)) (pz (+ (aref z row) rz)))
                    (declare (type single-float a b c rx ry rz px py pz))
                    (multiple-value-bind (ix iy iz axis step) (corner-first-solid probe px py pz ux uy uz reach)
                      (declare (type fixnum ix iy iz axis step))
                      (when (>= axis 0)
                        (add-corner-face-point set probe row h slot corner px py pz rx ry rz
                                               ix iy iz axis step))))))))))))
  set)
;; Fast boxes sweep their corners through the cells:1 ends here

;; [[file:../physics.org::#BXPUSH][A posted box pushes a box:1]]
(defconstant +posted-push-share+ 0.1
  "The share of the push-out speed a posted box may give a box body in a substep, beyond what
gravity gives it in one. #BXPUSH")

(declaim (inline mark-posted-points))
(defun mark-posted-points (points start dummy kx ky kz speed)
  "Give each of POINTS from START, found against a posted box moving at KX KY KZ, that velocity
as the first side's point velocity less the second's loses it (its sign turned where the first
side is the DUMMY row), the velocity along the point's normal, and SPEED as its cap. #BXPUSH"
  (declare (type box-point-columns points) (type index start dummy)
           (type single-float kx ky kz speed) #.+kernel-policy+)
  (with-box-point-columns ((first row) nx ny nz kvx kvy kvz kvn push-cap) points
    (loop for k of-type index from start below (box-point-columns-length points)
          do (let* ((sign (if (= (aref first k) dummy) -1.0 1.0))
                    (sx (* sign kx)) (sy (* sign ky)) (sz (* sign kz))
                    (along (+ (* (aref nx k) sx) (* (aref ny k) sy) (* (aref nz k) sz))))
               (declare (type single-float sign sx sy sz along))
               (setf (aref kvx k) sx (aref kvy k) sy (aref kvz k) sz (aref kvn k) along
                     (aref push-cap k) speed))))
  nil)

(defun find-box-posted-points (world set row reach dt push-max weight)
  "Append to SET's points those between the box at awake ROW of WORLD and each posted box its
filter meets within REACH plus their relative travel over DT: the separating-axis test's points
(box-pair-points, the posted box's side the dummy row), each given the posted box's velocity,
that velocity along its normal, and as its cap the speed +posted-push-share+ of PUSH-MAX and
WEIGHT (gravity times the substep), made an impulse by cap-posted-box-points. #BXPUSH"
  (declare (type box-set set) (type index row) (type single-float reach dt push-max weight) #.+kernel-policy+)
  (let* ((boxes (physics-world-boxes world)) (awake (physics-world-awake world))
         (speed (+ (* +posted-push-share+ push-max) weight))
         (dummy (body-columns-length awake)) (points (box-set-points set))
         (filtering (physics-world-filtering world)))
    (declare (type single-float speed))
    (with-body-columns (x y z qw qx qy qz radius handle flags vx vy vz) awake
      (let* ((owner (aref handle row)) (slot (handle-index owner))
             (cx (aref x row)) (cy (aref y row)) (cz (aref z row)) (r (aref radius row))
             (hx (aref (box-set-hx set) slot)) (hy (aref (box-set-hy set) slot)) (hz (aref (box-set-hz set) slot)))
        (declare (type single-float cx cy cz r hx hy hz))
        (with-box-columns (min-x min-y min-z max-x max-y max-z (ux vx) (uy vy) (uz vz) id filter) boxes
          (dotimes (b (box-columns-length boxes))
            (when (rows-meet-p filtering (aref flags row) (ash (aref filter b) +flag-filter-shift+))
              (let* ((kx (aref ux b)) (ky (aref uy b)) (kz (aref uz b))
                     (wx (- (aref vx row) kx)) (wy (- (aref vy row) ky)) (wz (- (aref vz row) kz))
                     (reach (+ reach (* dt (fsqrt (+ (* wx wx) (* wy wy) (* wz wz))))))
                     ;; the body's holding sphere against the posted box, grown by the reach
                     (ox (max 0.0 (- (aref min-x b) cx) (- cx (aref max-x b))))
                     (oy (max 0.0 (- (aref min-y b) cy) (- cy (aref max-y b))))
                     (oz (max 0.0 (- (aref min-z b) cz) (- cz (aref max-z b))))
                     (far (+ r reach)))
                (declare (type single-float kx ky kz wx wy wz reach ox oy oz far))
                (when (< (+ (* ox ox) (* oy oy) (* oz oz)) (* far far))
                  (let ((start (box-point-columns-length points))
                        (base (logior (ash slot 34) (ash 1 32) (ash 1 31) (ash (ldb (byte 15 0) (aref id b)) 16))))
                    (box-pair-points set owner base row dummy reach cx cy cz
                                     (aref qw row) (aref qx row) (aref qy row) (aref qz row) hx hy hz
                                     (* 0.5 (+ (aref min-x b) (aref max-x b))) (* 0.5 (+ (aref min-y b) (aref max-y b)))
                                     (* 0.5 (+ (aref min-z b) (aref max-z b))) 1.0 0.0 0.0 0.0
                                     (* 0.5 (- (aref max-x b) (aref min-x b))) (* 0.5 (- (aref max-y b) (aref min-y b)))
                                     (* 0.5 (- (aref max-z b) (aref min-z b))))
                    (mark-posted-points points start dummy kx ky kz speed))))))))))
  set)

(defun cap-posted-box-points (set)
  "Turn the speed cap of each of SET's points against a posted box into an impulse, times the
point's normal mass; the others keep the largest single-float. #BXPUSH"
  (declare (type box-set set) #.+kernel-policy+)
  (let ((points (box-set-points set)))
    (with-box-point-columns (push-cap normal-mass) points
      (dotimes (k (box-point-columns-length points))
        (when (< (aref push-cap k) most-positive-single-float)
          (setf (aref push-cap k) (* (aref normal-mass k) (aref push-cap k)))))))
  set)
;; A posted box pushes a box:1 ends here

;; [[file:../physics.org::#ST0R3S][Store impulses, events and the step's error:1]]
(declaim (inline held-marking-p mark-held))
(defun held-marking-p (world)
  "True when this step's store phase marks which awake rows are held by sleepers alone: sleep is
on and some body sleeps. #ST0R3S"
  (and (physics-world-sleep-enabled world)
       (plusp (body-columns-length (physics-world-sleeping world)))))

(defun mark-held (held kind handle-a handle-b ids c row-a row-b n)
  "Note in HELD what contact C, between solver rows ROW-A and ROW-B (N is the dummy row), tells
of its awake side: bit 1 when it leans on a sleeper, bit 2 when its other side moves (an awake
body, braced or not, or a box). Terrain notes nothing. #ST0R3S"
  (declare (type fixnum-column held kind handle-a handle-b) (type handle-table ids)
           (type index c row-a row-b n))
  (cond ((and (< row-a n) (< row-b n))
         (setf (aref held row-a) (logior (aref held row-a) 2)
               (aref held row-b) (logior (aref held row-b) 2)))
        ((= (aref kind c) +contact-terrain+))
        (t (let* ((row (min row-a row-b))
                  (other (if (= row-a n) (aref handle-a c) (aref handle-b c)))
                  (lean (and (= (aref kind c) +contact-pair+)
                             (= (aref (handle-table-set ids) (handle-index other)) +set-sleeping+))))
             (setf (aref held row) (logior (aref held row) (if lean 1 2)))))))

(defmacro store-contact-row ()
  "Store row K, of contact C: its impulses into the contact, its mark when the piece MARKs, the
step's deepest gap and fastest approach, its touch and hit events: expanded in the store phase's
piece, with its variables. #ST0R3S"
  `(let* ((base (constraint-base k))
          (c (aref contact k))
          (g (geometry-start c))
          (pushed (if-feature (:or :contact-events :hit-events) (> (@ max-normal-impulse) 0.0) nil))
          (a (solver-row (aref body-a k))) (b (solver-row (aref body-b k)))
          (x (@ nx)) (y (@ ny)) (z (@ nz))
          ;; the gap the last relax pass kept, less the slop the prepared gap carries
          (gap (- (@ gap) slop))
          ;; without body contacts the other side is the dummy row, whose velocity is
          ;; the zero the prepare phase wrote, which no one-sided kernel changes
          (vn (+ (* (- (if-feature :body-contacts (aref v b) 0.0) (aref v a)) x)
                 (* (- (if-feature :body-contacts (aref v (+ b 1)) 0.0) (aref v (+ a 1))) y)
                 (* (- (if-feature :body-contacts (aref v (+ b 2)) 0.0) (aref v (+ a 2))) z)
                 (if-feature :boxes (@ kvn) 0.0))))
     (declare (type fixnum c) (type index base g) (ignorable pushed b))
     (setf (contact-at geometry g normal-impulse) (@ normal-impulse)
           (contact-at geometry g tangent-impulse-1) (@ tangent-impulse-1) (contact-at geometry g tangent-impulse-2) (@ tangent-impulse-2))
     ;; without rolling resistance the contact's rolling impulses stay the zeros it was
     ;; made with
     (if-feature :rolling-resistance
       (setf (contact-at geometry g rolling-impulse-x) (@ rolling-impulse-x) (contact-at geometry g rolling-impulse-y) (@ rolling-impulse-y)
             (contact-at geometry g rolling-impulse-z) (@ rolling-impulse-z)))
     ;; and the spin impulse, for the next step's first substep to start from it: only
     ;; a row with no radius on side b has one, and no other row's side block is read
     (if-feature :friction
       (when (= (@ rb) 0.0) (setf (contact-at geometry g spin-impulse) (@ spin-impulse))))
     (when mark (mark-held held kind handle-a handle-b ids c (aref body-a k) (aref body-b k) n))
     (when (< gap 0.0)
       (setf max-penetration (max max-penetration (- gap))
             max-approach (max max-approach (- vn))))
     (store-touch-event)
     (store-hit-event)))

(defmacro store-touch-event ()
  "A :begin or :end event for row K's contact C when whether it pushed this step (PUSHED) differs
from whether it touched: expanded in the store phase's piece of WORKER, with its variables. #ST0R3S"
  `(if-feature :contact-events
   (unless (eq pushed (= (aref touching c) 1))
     (setf (aref touching c) (if pushed 1 0))
     (push-piece-event world worker (if pushed +event-begin+ +event-end+) (aref handle-a c) (aref handle-b c)
                 (contact-at geometry g px) (contact-at geometry g py) (contact-at geometry g pz) (- (@ relative-velocity))
                 (and (= (aref kind c) +contact-box+) (box-owner world (aref key c)))))))

(defmacro store-hit-event ()
  "A :hit event for row K's contact C when it pushed and arrived faster than the hit speed, for
a box's contact or a body that reports hits: expanded in the store phase's piece of WORKER, with
its variables. #ST0R3S"
  `(if-feature :hit-events
   (when (and pushed (> (- (@ relative-velocity)) hit-speed)
              (or (= (aref kind c) +contact-box+)
                  (flet ((reports (h)
                           (and (>= h 0)
                                (let ((set (aref (handle-table-set ids) (handle-index h)))
                                      (row (aref (handle-table-local ids) (handle-index h))))
                                  (logtest +flag-report-hits+
                                           (aref (body-columns-flags (if (= set +set-awake+) awake sleeping))
                                                 row))))))
                    (or (reports (aref handle-a c)) (reports (aref handle-b c))))))
     (push-piece-event world worker +event-hit+ (aref handle-a c) (aref handle-b c)
                 (contact-at geometry g px) (contact-at geometry g py) (contact-at geometry g pz) (- (@ relative-velocity))
                 (and (= (aref kind c) +contact-box+) (box-owner world (aref key c)))))))

(define-featured-kernel (store-phase :features (:body-contacts :boxes :friction :contact-events :hit-events :rolling-resistance)) (world)
  "The store phase: copy each constraint's impulses back to its contact, note touching flips as :begin
and :end, hard arrivals as :hit, and measure the step's largest penetration and approach
speed; in a world with sleepers, mark the awake rows that only sleepers and terrain touch
(mark-held), for the finalize phase's sleep. From here on the step changes what it cannot undo,
so its undo log closes. #ST0R3S"
  (setf (physics-world-undo-open world) nil)
  (with-world-parameters (hit-speed slop) world
    (let* ((cbuf (physics-world-constraints world))
           (contacts (physics-world-contacts world))
           (v (physics-world-velocities world))
           (ids (physics-world-ids world))
           (awake (physics-world-awake world))
           (sleeping (physics-world-sleeping world))
           (max-penetration 0.0) (max-approach 0.0)
           ;; each piece's two figures ([[#SPL1T5]])
           ;; two for each of the most workers a world may have, +physics-max-workers+
           (maxima (make-array 128 :element-type 'single-float :initial-element 0.0))
           (n (body-columns-length awake))
           (held (physics-world-held world))
           ;; only sleep looks at the marks, and only a world with sleepers makes lean contacts;
           ;; without body contacts and boxes every contact is terrain's, which marks nothing
           (marking (if-feature (:or :body-contacts :boxes) (held-marking-p world) nil)))
      (declare (type f32-column v) (type single-float hit-speed slop max-penetration max-approach)
               (type index n) (type fixnum-column held) (type f32-column maxima) (dynamic-extent maxima)
               (ignorable ids awake sleeping) #.+kernel-policy+)
      (when marking (fill held 0 :end (1+ n)))
      (with-constraint-block (contact body-a body-b) cbuf
        (with-contact-columns (touching kind handle-a handle-b key geometry) contacts
          (declare (ignorable touching kind handle-a handle-b key))
          ;; each row writes its own contact, so the rows may be cut into pieces, one a worker,
          ;; each with its own figures and events, merged in the pieces' order ([[#SPL1T5]]);
          ;; the marks, which rows share, are set by one worker
          (flet ((store-piece (worker count)
                   (declare (type fixnum worker count))
                   (let ((max-penetration 0.0) (max-approach 0.0) (mark (and marking (= count 1))))
                     (declare (type single-float max-penetration max-approach))
                     (multiple-value-bind (from to) (piece-bounds 0 (constraint-columns-length cbuf) worker count)
                       (declare (type index from to))
                       (loop for k of-type index from from below to
                             unless (< (aref contact k) 0) do (store-contact-row)))
                     (setf (aref maxima (* 2 worker)) max-penetration
                           (aref maxima (1+ (* 2 worker))) max-approach))))
            (declare (dynamic-extent #'store-piece))
            (let ((pieces (run-pieces world (constraint-columns-length cbuf) :store #'store-piece)))
              (declare (type fixnum pieces))
              (dotimes (w pieces)
                (setf max-penetration (max max-penetration (aref maxima (* 2 w)))
                      max-approach (max max-approach (aref maxima (1+ (* 2 w))))))
              (when (and marking (> pieces 1))
                (dotimes (k (constraint-columns-length cbuf))
                  (let ((c (aref contact k)))
                    (unless (< c 0)
                      (mark-held held kind handle-a handle-b ids c (aref body-a k) (aref body-b k) n)))))))))
      (let ((stats (world-statistics world)))
        (setf (step-statistics-max-penetration stats) (coerce max-penetration 'double-float)
              (step-statistics-max-approach stats) (coerce max-approach 'double-float)))
      world)))
;; Store impulses, events and the step's error:1 ends here

;; [[file:../physics.org::#F1NAL5][Finalize: positions, orientation, age and sleep:1]]
(defun fold-positions (awake d check near held)
  "Fold the solver's deltas D into AWAKE's positions, in a loop that calls nothing. When CHECK, a
row whose delta is longer than its note in NEAR (every row, when CHECK is :all) is not moved but
listed in HELD, for hold-out-of-cells to check its path and fold it; return how many rows are
listed. #F1NAL5"
  (declare (type body-columns awake) (type f32-column d near) (type fixnum-column held) #.+kernel-policy+)
  (let ((listed 0))
    (declare (type index listed))
    (with-body-columns (x y z) awake
      (dotimes (i (body-columns-length awake) listed)
        (let* ((p (delta-row i)) (dx (aref d p)) (dy (aref d (+ p 1))) (dz (aref d (+ p 2))))
          (if (and check (or (eq check :all) (> (+ (* dx dx) (* dy dy) (* dz dz)) (aref near i))))
              (setf (aref held listed) i listed (1+ listed))
              (setf (aref x i) (+ (aref x i) dx) (aref y i) (+ (aref y i) dy) (aref z i) (+ (aref z i) dz))))))))

(defun fold-solver-state (awake v dt &optional turned (from 0) (to (body-columns-length awake)))
  "Fold the solver's velocities V into AWAKE's rows FROM below TO (all of them by default), and
turn each one's orientation by its angular velocity over DT, but, when TURNED, a jointed
sphere's, which the substeps turned ([[#J0TURN]]). Two loops that call nothing, each reading and
writing at most eight arrays; with fold-positions, three. Each row is its own, so the rows may
be folded in pieces. #F1NAL5"
  (declare (type body-columns awake) (type f32-column v) (type single-float dt) (type index from to)
           #.+kernel-policy+)
  (with-body-columns (vx vy vz wx wy wz) awake
    (loop for i of-type index from from below to
          do (let ((o (solver-row i)))
               (setf (aref vx i) (aref v o) (aref vy i) (aref v (+ o 1)) (aref vz i) (aref v (+ o 2))
                     (aref wx i) (aref v (+ o 3)) (aref wy i) (aref v (+ o 4)) (aref wz i) (aref v (+ o 5))))))
  ;; q += dt/2 (0,w) q, then normalise; when TURNED, a loop of its own that leaves the jointed
  ;; spheres out, so that a world without joints runs the loop it always ran
  (with-body-columns (qw qx qy qz flags) awake
    (macrolet ((turn-rows (skip)
                 `(loop for i of-type index from from below to
                        do (unless ,skip
                             (turn-row-orientation v i (* 0.5 dt) qw qx qy qz)))))
      (if turned
          (turn-rows (= (logand (aref flags i) (logior +flag-jointed+ +flag-box-shape+)) +flag-jointed+))
          (turn-rows nil)))))

(defconstant +departure-none+ 0
  "A row's fate in the finalize phase's first pass: it stays awake. #F1NAL5")

(defconstant +departure-escaped+ 1
  "A row's fate in the finalize phase's first pass: its centre crossed the coordinate limit, and
it is removed with an :escaped event. #F1NAL5")

(defconstant +departure-expired+ 2
  "A row's fate in the finalize phase's first pass: a mortal body reached its life, and it is
removed with an :expired event. #F1NAL5")

(defconstant +departure-asleep+ 3
  "A row's fate in the finalize phase's first pass: still for long enough, it goes to sleep. #F1NAL5")

(defmacro stillness-fate ()
  "The fate of awake row I, neither escaped nor expired, in a world that sleeps: +departure-asleep+
once it has been still for the time to sleep, else +departure-none+, counting its still time or
setting it back to zero. Expanded in finalize-phase's first pass, whose names it reads. #F1NAL5"
  `(let* ((p (delta-row i))
          (ddx (aref d p)) (ddy (aref d (+ p 1))) (ddz (aref d (+ p 2)))
          (ax (aref wx i)) (ay (aref wy i)) (az (aref wz i))
          (speed (+ (fsqrt (+ (* (aref vx i) (aref vx i)) (* (aref vy i) (aref vy i))
                             (* (aref vz i) (aref vz i))))
                    (* (aref radius i) (fsqrt (+ (* ax ax) (* ay ay) (* az az))))))
          (drift (* 0.5 inv-dt (fsqrt (+ (* ddx ddx) (* ddy ddy) (* ddz ddz))))))
     ;; a body only sleepers and terrain touch is judged by its displacement alone
     (cond ((not (and (< (if (and marked (= (aref held i) 1)) drift (max speed drift)) sleep-speed)
                      (not (and settle-p (logtest (aref settling i) +brace-unsettled+)))))
            (setf (aref sleep-time i) 0.0)
            +departure-none+)
           ;; a jointed body sleeps with its group ([[#J0SL3P]])
           ((and (>= (incf (aref sleep-time i) dt) time-to-sleep)
                 (not (logtest (aref flags i) +flag-jointed+)))
            +departure-asleep+)
           (t +departure-none+))))

(define-featured-kernel (finalize-phase :features (:body-contacts :boxes :sleep :mortal)) (world)
  "The finalize phase, last of the step: fold deltas into positions and solver velocities into the rows, turn orientations,
age mortal bodies (sleepers too) and expire them, and put bodies still for long enough to
sleep: one pass decides which rows leave the awake set, the next moves them, both from the last
row down, so relocation never skips one. Compiled for fewer
features it holds no ageing without :mortal, no sleep without :sleep, and no reading of the
store phase's marks without body contacts and boxes, which alone make them. #F1NAL5"
  (let* ((awake (physics-world-awake world))
         (sleeping (physics-world-sleeping world))
         (v (physics-world-velocities world))
         (d (physics-world-deltas world))
         (dt (physics-world-current-dt world))
         (inv-dt (/ 1.0 dt))
         (sleep-p (if-feature :sleep (physics-world-sleep-enabled world) nil))
         (sleep-speed (f32 (physics-world-sleep-speed world)))
         (time-to-sleep (f32 (physics-world-time-to-sleep world)))
         (limit (f32 +physics-coordinate-limit+))
         ;; the store phase's marks, read before any row moves (held-marking-p)
         (marked (if-feature (:or :body-contacts :boxes) (and sleep-p (held-marking-p world)) nil))
         (held (physics-world-held world))
         (settling (physics-world-braced world))
         (settle-p (= (physics-world-braced-step world) (physics-world-step-count world)))
         ;; the sleepers before this step's fall asleep: a body falling asleep below was aged
         ;; in the awake rows, and the sleepers' walk must not age it again
         (asleep-before (body-columns-length sleeping)))
    (declare (type f32-column v d) (type single-float dt inv-dt sleep-speed time-to-sleep limit)
             (type fixnum-column settling) (type index asleep-before) (ignorable asleep-before)
             (type body-columns awake sleeping) (type fixnum-column held)
             (ignorable inv-dt sleep-speed time-to-sleep held) #.+kernel-policy+)
    ;; the deltas into the positions, but for the rows whose path may meet a solid cell: their
    ;; paths are checked first ([[#SQU33Z]])
    (multiple-value-bind (check near held) (path-check-notes world)
      (hold-out-of-cells world held (fold-positions awake d check near held)))
    ;; the velocities and turns, row by row, in pieces, one a worker ([[#SPL1T5]])
    (let ((turned (joints-turned-p world)))
      (flet ((fold (from to) (fold-solver-state awake v dt turned from to)))
        (declare (dynamic-extent #'fold))
        (run-row-pieces world (body-columns-length awake) :fold #'fold)))
    ;; a box whose points were solved turns by its substeps' turns ([[#BXSOLV]])
    (when (physics-world-box-bodies world) (turn-box-orientations world))
    ;; then ageing and sleep, in two passes: the first decides, in a loop that calls nothing,
    ;; which rows leave the awake set and why, and lists them from the last down; the second
    ;; moves them in that order, so a relocation only ever moves a row already dealt with
    (let ((leaving (fixnum-room (physics-world-departures world) (* 2 (body-columns-length awake))))
          (departures 0))
      (declare (type fixnum-column leaving) (type index departures))
      (setf (physics-world-departures world) leaving)
      (with-body-columns (x y z vx vy vz wx wy wz radius sleep-time age life flags) awake
        (declare (ignorable vx vy vz wx wy wz radius sleep-time age life flags))
        (loop for i of-type fixnum from (1- (body-columns-length awake)) downto 0 do
          (let ((fate
                  (cond ((or (>= (abs (aref x i)) limit) (>= (abs (aref y i)) limit) (>= (abs (aref z i)) limit))
                         +departure-escaped+)
                        ((if-feature :mortal (and (> (aref life i) 0.0) (>= (incf (aref age i) dt) (aref life i))) nil)
                         +departure-expired+)
                        (sleep-p (stillness-fate))
                        (t +departure-none+))))
            (declare (type fixnum fate))
            (unless (= fate +departure-none+)
              (setf (aref leaving departures) i (aref leaving (1+ departures)) fate)
              (incf departures 2)))))
      (with-body-columns (x y z handle) awake
        (loop for j of-type index from 0 below departures by 2 do
          (let ((i (aref leaving j)))
            (declare (type index i))
            (let ((fate (aref leaving (1+ j))))
              (cond ((= fate +departure-escaped+)
                     (push-event world +event-escaped+ (aref handle i) +no-body+ (aref x i) (aref y i) (aref z i) 0.0)
                     (%remove-body world +set-awake+ i))
                    ((= fate +departure-expired+)
                     (push-event world +event-expired+ (aref handle i) +no-body+ (aref x i) (aref y i) (aref z i) 0.0)
                     (%remove-body world +set-awake+ i))
                    (t (sleep-physics-body world i))))))))
    ;; only a world with a mortal sleeper walks the sleeping buffer, and only its rows that
    ;; slept before this step: a removal below moves the last row, one of them or one just
    ;; asleep, into a place already walked
    (when (if-feature :mortal (plusp (physics-world-mortal-sleepers world)) nil)
    (with-body-columns (x y z age life handle) sleeping
      (loop for i of-type fixnum from (1- asleep-before) downto 0 do
        (when (and (> (aref life i) 0.0) (>= (incf (aref age i) dt) (aref life i)))
          (push-event world +event-expired+ (aref handle i) +no-body+ (aref x i) (aref y i) (aref z i) 0.0)
          (%remove-body world +set-sleeping+ i)))))
    ;; joints over their force break, and still joint groups sleep ([[#J0SL3P]])
    (when (physics-world-joints world) (finish-joints world))
    world))
;; Finalize: positions, orientation, age and sleep:1 ends here

;; [[file:../physics.org::#SQU33Z][Squeezed between a box and the cells: the box yields, the cells hold:1]]
(defun note-box-rows (world)
  "Collect the constraint rows of this step's box contacts into WORLD's box rows, each with its
cap: the normal impulse that changes its body's speed along the normal by the speed at which body
and box close along it at the start of the step, plus the push-out speed, plus what gravity adds
in a substep. Return how many rows there are. #SQU33Z"
  (declare #.+kernel-policy+)
  (let* ((cbuf (physics-world-constraints world))
         (kinds (contact-columns-kind (physics-world-contacts world)))
         (awake (physics-world-awake world))
         (push-max (f32 (physics-world-push-max world)))
         (weight (gravity-step world (physics-world-current-h world)))
         (count 0))
    (declare (type fixnum-column kinds) (type single-float push-max weight) (type index count))
    (with-constraint-block (contact body-a) cbuf
      (with-body-columns (vx vy vz) awake
        (dotimes (k (constraint-columns-length cbuf))
          (let ((c (aref contact k)))
            (when (and (>= c 0) (= (aref kinds c) +contact-box+))
              (let* ((base (constraint-base k))
                     (a (aref body-a k))
                     ;; how fast body and box close along the normal at the start of the step:
                     ;; the box's velocity along it is kvn once the frames are prepared
                     (closing (max 0.0 (- (+ (* (aref vx a) (@ nx)) (* (aref vy a) (@ ny)) (* (aref vz a) (@ nz)))
                                          (@ kvn)))))
                (declare (type index base a) (type single-float closing))
                (when (>= count (length (physics-world-box-rows world)))
                  (let ((size (* 2 (1+ count))))
                    (setf (physics-world-box-rows world)
                          (replace (make-array size :element-type 'fixnum :initial-element 0) (physics-world-box-rows world))
                          (physics-world-box-caps world)
                          (replace (make-array size :element-type 'single-float :initial-element 0.0)
                                   (physics-world-box-caps world)))))
                (setf (aref (the fixnum-column (physics-world-box-rows world)) count) k
                      (aref (the f32-column (physics-world-box-caps world)) count)
                      (* (@ normal-mass) (+ closing push-max weight)))
                (incf count)))))))
    count))

(defun yield-box-pushes (world count)
  "Hold the accumulated normal impulse of each of WORLD's first COUNT box rows to its cap, and
take back from its body the push beyond the cap. Return true when some row was held. #SQU33Z"
  (declare (type index count) #.+kernel-policy+)
  (let ((cbuf (physics-world-constraints world))
        (v (physics-world-velocities world))
        (rows (physics-world-box-rows world))
        (caps (physics-world-box-caps world))
        (yielded nil))
    (declare (type f32-column v caps) (type fixnum-column rows))
    (with-constraint-block (contact body-a) cbuf
      (dotimes (j count yielded)
        (let* ((k (aref rows j)) (base (constraint-base k))
               (l (@ normal-impulse)) (cap (aref caps j)))
          (declare (type index k base) (type single-float l cap))
          (when (> l cap)
            ;; the pass pushed body a along -n by its inverse mass times the impulse
            (let ((o (solver-row (aref body-a k))) (back (* (@ ima) (- l cap))))
              (declare (type index o) (type single-float back))
              (setf yielded t
                    (@ normal-impulse) cap
                    (aref v o) (+ (aref v o) (* back (@ nx)))
                    (aref v (+ o 1)) (+ (aref v (+ o 1)) (* back (@ ny)))
                    (aref v (+ o 2)) (+ (aref v (+ o 2)) (* back (@ nz)))))))))))

(defun mark-squeezed-rows (world count)
  "Note in WORLD's squeezed column, for its awake rows, 1 for the body of each of its first COUNT
box rows and for both bodies of each two-body constraint whose kept gap is deeper than the
slop, and 0 for every other row. #SQU33Z"
  (declare (type index count) #.+kernel-policy+)
  (let* ((n (body-columns-length (physics-world-awake world)))
         (cbuf (physics-world-constraints world))
         (rows (physics-world-box-rows world))
         (marks (let ((m (physics-world-squeezed world)))
                  (if (> (length m) n)
                      m
                      (setf (physics-world-squeezed world) (make-array (* 2 (1+ n)) :element-type 'fixnum))))))
    (declare (type index n) (type fixnum-column rows marks))
    (fill marks 0 :end (1+ n))
    (with-constraint-block (contact body-a body-b) cbuf
      (dotimes (j count)
        (setf (aref marks (aref body-a (aref rows j))) 1))
      (dotimes (k (constraint-columns-length cbuf))
        (let ((base (constraint-base k)) (a (aref body-a k)) (b (aref body-b k)))
          (declare (type index base a b))
          ;; the kept gap carries the slop ([[#ST0R3S]]): below zero, deeper than a slop
          (when (and (< a n) (< b n) (< (@ gap) 0.0))
            (setf (aref marks a) 1 (aref marks b) 1)))))
    marks))

(defun squeeze-speed-limit (world)
  "The fastest speed a squeezed body of WORLD may leave a substep with: the fastest box posted for
the step plus the push-out speed. #SQU33Z"
  (let ((boxes (physics-world-boxes world)) (fastest 0.0))
    (declare (type single-float fastest))
    (with-box-columns (vx vy vz) boxes
      (dotimes (b (box-columns-length boxes))
        (setf fastest (max fastest (fsqrt (+ (* (aref vx b) (aref vx b)) (* (aref vy b) (aref vy b))
                                             (* (aref vz b) (aref vz b))))))))
    (+ fastest (f32 (physics-world-push-max world)))))

(defun path-check-notes (world)
  "What the finalize phase needs to check WORLD's paths ([[#SQU33Z]]): whether to check them (NIL
without terrain, :all when the terrain phase did not note this step's rows, else T), the terrain
phase's notes, and the array for the rows held back, at least as long as the awake rows. #SQU33Z"
  (let ((n (body-columns-length (physics-world-awake world))))
    (when (< (length (physics-world-held-rows world)) (1+ n))
      (setf (physics-world-held-rows world) (make-array (* 2 (1+ n)) :element-type 'fixnum :initial-element 0)))
    (values (cond ((null (physics-world-terrain world)) nil)
                  ((= (physics-world-near-cells-step world) (physics-world-step-count world)) t)
                  (t :all))
            (physics-world-near-cells world)
            (physics-world-held-rows world))))

(declaim (inline path-outruns-look-p surface-stop))

(defun path-outruns-look-p (moved2 r vx vy vz margin limit dt gstep)
  "Whether a body of radius R, moving at VX VY VZ at the start of a step of DT seconds (gravity
adding GSTEP), moved the square root of MOVED2: farther than the terrain phase looked, past its
MARGIN and past the travel that velocity promised (step-reach, at most LIMIT). #SQU33Z"
  (declare (type single-float moved2 r vx vy vz margin limit dt gstep))
  (and (> moved2 (* margin margin))
       (let ((looked (- (body-reach r (step-travel vx vy vz dt gstep) margin limit) r)))
         (> moved2 (* looked looked)))))

(defun surface-stop (at r along)
  "How far along its path a sphere of radius R goes before its surface reaches a face's plane,
which its centre reaches at AT, its path's unit direction having the component ALONG across the
face; 0 when the surface is past the plane already. #SQU33Z"
  (declare (type single-float at r along))
  (max 0.0 (- at (/ r (max (abs along) 1e-6)))))

(defun hold-out-of-cells (world rows count)
  "Check the path of each of WORLD's awake rows listed in the first COUNT entries of ROWS, then fold
its delta into its position: a path that carries the centre into a solid cell, or, longer than
the terrain phase looked along, the surface through the face of one, is cut where the surface
reaches that face (at the start, if it is already past it), the velocity into the face removed
and a :held-out event reported. Return how many bodies were held. #SQU33Z"
  (declare (type fixnum-column rows) (type index count) #.+kernel-policy+)
  (let* ((held 0)
         (awake (physics-world-awake world))
         (probe (physics-world-probe world))
         (v (physics-world-velocities world))
         (d (physics-world-deltas world))
         (margin (f32 (physics-world-margin world)))
         (limit (f32 (physics-world-reach-limit world)))
         (dt (physics-world-current-dt world))
         (gstep (gravity-step world dt)))
    (declare (type fixnum held) (type f32-column v d) (type single-float margin limit dt gstep))
    (with-body-columns (x y z vx vy vz radius handle) awake
      (dotimes (j count)
        (let* ((i (aref rows j))
               (p (delta-row i))
               (dx (aref d p)) (dy (aref d (+ p 1))) (dz (aref d (+ p 2)))
               (moved2 (+ (* dx dx) (* dy dy) (* dz dz)))
               (cx (aref x i)) (cy (aref y i)) (cz (aref z i)) (r (aref radius i))
               (long (path-outruns-look-p moved2 r (aref vx i) (aref vy i) (aref vz i) margin limit dt gstep)))
          (declare (type index i p) (type single-float dx dy dz moved2 cx cy cz r))
          ;; within the look-ahead, a path that stays in the centre's cell stays in the air
          (when (or long
                    (/= (cell-floor cx) (cell-floor (+ cx dx)))
                    (/= (cell-floor cy) (cell-floor (+ cy dy)))
                    (/= (cell-floor cz) (cell-floor (+ cz dz))))
            (let* ((len (fsqrt moved2)) (inv (/ 1.0 (max len 1e-12)))
                   (ux (* dx inv)) (uy (* dy inv)) (uz (* dz inv)))
              (declare (type single-float len inv ux uy uz))
              (multiple-value-bind (axis at) (first-solid-on-ray probe cx cy cz ux uy uz (if long (+ len r) len))
                (declare (type (integer -1 2) axis) (type single-float at))
                (unless (< axis 0)
                  (let* ((along (case axis (0 ux) (1 uy) (t uz)))
                         ;; where the surface reaches the face's plane, along the path
                         (stop (surface-stop at r along))
                         (o (+ (solver-row i) axis))
                         (into (if (> along 0.0) (max 0.0 (aref v o)) (min 0.0 (aref v o)))))
                    (declare (type single-float along stop into) (type index o))
                    (when (< stop len)
                      (setf (aref d p) (* ux stop) (aref d (+ p 1)) (* uy stop) (aref d (+ p 2)) (* uz stop)
                            (aref v o) (- (aref v o) into))
                      (incf held)
                      (push-event world +event-held-out+ (aref handle i) +no-body+
                                  (+ cx (* ux at)) (+ cy (* uy at)) (+ cz (* uz at)) (abs into))))))))
          ;; then the fold, as for every other row
          (setf (aref x i) (+ cx (aref d p)) (aref y i) (+ cy (aref d (+ p 1))) (aref z i) (+ cz (aref d (+ p 2)))))))
    (setf (physics-world-held-out-count world) held)
    held))

(defun physics-world-last-step-held-out-count (world)
  "How many bodies the last step stopped at the face of a solid cell. #SQU33Z"
  (check-world world 'physics-world-last-step-held-out-count)
  (physics-world-held-out-count world))

(defun physics-world-last-step-buried-count (world)
  "How many awake bodies began the last step with their centre in a solid cell, and were pushed
toward the air by that cell's contact. #SQU33Z"
  (check-world world 'physics-world-last-step-buried-count)
  (physics-world-buried-count world))
;; Squeezed between a box and the cells: the box yields, the cells hold:1 ends here

;; [[file:../physics.org::#IDVK7G][The step as built:1]]
(defun reset-phase (world)
  "The reset phase, first of the step: empty the event buffer, make the probe forget its borrowed chunks, count the step
and start the contact table's walk of it. #IDVK7G"
  (event-columns-clear (physics-world-events world))
  (fill (physics-world-event-data world) nil)
  (reset-terrain-probe (physics-world-probe world) (physics-world-terrain world))
  (incf (physics-world-step-count world))
  (incf (physics-world-rows-version world))
  (let ((table (physics-world-contact-table world)))
    (setf (contact-table-step table) (physics-world-step-count world)
          (contact-table-cursor table) 0 (contact-table-touched table) 0))
  world)

(declaim (inline physics-world-max-penetration))
(defun physics-world-max-penetration (world)
  "The deepest overlap, in metres, left at the end of the last step. #IDVK7G"
  (check-world world 'physics-world-max-penetration)
  (step-statistics-max-penetration (world-statistics world)))

(defun mark-held-rows (world)
  "When an awake row of WORLD is crowded (its overlap count has reached +overlaps-per-body+),
raise to that count the count of every awake row with a pair contact deeper than the slop, so
that the count marks every row the step holds, and return true; else change nothing and return
false. #IDVK7G"
  (declare #.+kernel-policy+)
  (let* ((contacts (physics-world-contacts world))
         (geometry (contact-columns-geometry contacts))
         (kinds (contact-columns-kind contacts))
         (as (contact-columns-handle-a contacts)) (bs (contact-columns-handle-b contacts))
         (ids (physics-world-ids world)) (sets (handle-table-set ids)) (locals (handle-table-local ids))
         (overlaps (pair-list-overlaps (physics-world-pair-list world)))
         (deep (- (f32 (physics-world-slop world)))))
    (declare (type fixnum-column kinds as bs sets locals overlaps) (type f32-column geometry)
             (type single-float deep))
    (flet ((hold (h)
             (declare (type fixnum h))
             (let ((slot (handle-index h)))
               (when (= (aref sets slot) +set-awake+)
                 (setf (aref overlaps (aref locals slot)) +overlaps-per-body+)))))
      (declare (inline hold))
      (when (loop for i of-type index below (body-columns-length (physics-world-awake world))
                  thereis (>= (aref overlaps i) +overlaps-per-body+))
        (dotimes (k (contact-columns-length contacts) t)
          (when (and (= (aref kinds k) +contact-pair+) (< (contact@ geometry k separation) deep))
            (hold (aref as k))
            (hold (aref bs k))))))))

(defun hold-row-speeds (world marks at-least limit)
  "Scale the solver's linear velocity of every awake row of WORLD whose entry in MARKS is at
least AT-LEAST down to LIMIT, when it is faster: the crowd's hold and the squeeze's ([[#SQU33Z]]). #IDVK7G"
  (declare (type fixnum-column marks) (type fixnum at-least) (type single-float limit) #.+kernel-policy+)
  (let ((v (physics-world-velocities world))
        (limit2 (* limit limit)))
    (declare (type f32-column v) (type single-float limit2))
    (dotimes (i (body-columns-length (physics-world-awake world)))
      (when (>= (aref marks i) at-least)
        (let* ((o (solver-row i)) (x (aref v o)) (y (aref v (+ o 1))) (z (aref v (+ o 2)))
               (s2 (+ (* x x) (* y y) (* z z))))
          (when (> s2 limit2)
            (let ((s (/ limit (fsqrt s2))))
              (setf (aref v o) (* x s) (aref v (+ o 1)) (* y s) (aref v (+ o 2)) (* z s)))))))))

(defun hold-crowded-speeds (world)
  "Scale the solver's linear velocity of every awake row whose overlap count has reached
+overlaps-per-body+ down to half the push-out speed, when it is faster. #IDVK7G"
  (hold-row-speeds world (pair-list-overlaps (physics-world-pair-list world)) +overlaps-per-body+
                   (* 0.5 (f32 (physics-world-push-max world)))))

(defun substep-phase (world)
  "The substep phase: the Soft Step substeps: integrate velocities, warm start, solve with bias,
integrate positions, relax without bias; in a crowded step (one with contacts in the overflow
colour, or after a step that left an overlap deeper than *physics-crowded-depth*), relax
*physics-crowded-relax-passes* more times, and when a body is crowded, hold the crowd's
bodies to half the push-out speed. #IDVK7G"
  (let* ((kernels (physics-world-kernels world))
         (h (physics-world-current-h world))
         (inv-h (/ 1.0 h))
         (crowded (or (plusp (physics-world-overflow-count world))
                      (> (f32 (physics-world-max-penetration world)) (f32 (physics-world-crowded-depth world)))))
         (relaxes (if crowded (1+ (the fixnum (physics-world-crowded-relax-passes world))) 1))
         (held (and crowded (mark-held-rows world)))
         ;; the box rows and their caps ([[#SQU33Z]]): none in a step where no body touched a box
         (boxed (if (= (physics-world-box-touch-step world) (physics-world-step-count world))
                    (note-box-rows world)
                    0))
         ;; the joints to solve, prepared, or NIL ([[#J0PREP]])
         (joints (and (physics-world-joints world) (prepare-joints world h)))
         ;; the boxes' points, found and prepared, or NIL ([[#BXSOLV]])
         (boxes (and (physics-world-box-bodies world) (prepare-box-points world h)))
         (v (physics-world-velocities world)) (d (physics-world-deltas world)))
    (declare (type single-float h inv-h) (type fixnum relaxes boxed))
    (let ((squeezed nil))
    (dotimes (i (physics-world-substeps world))
      (let ((elapsed (* h (float i 1.0))))
        (physics-integrate-velocities kernels world h)
        ;; the joints, when some are prepared, are solved inside the contacts' passes, colour
        ;; by colour with the contacts ([[#J0FAML]])
        (when boxes (warm-start-box-points boxes v))
        (physics-warm-start kernels world)
        (when boxes (setf (box-set-elapsed boxes) elapsed) (solve-box-points boxes v d inv-h t))
        (physics-solve-contacts kernels world inv-h t elapsed)
        (flet ((yield-boxes ()
                 ;; a box that yields squeezes what it presses: from then on the step holds it
                 (when (and (yield-box-pushes world boxed) (not squeezed))
                   (mark-squeezed-rows world boxed)
                   (setf squeezed (squeeze-speed-limit world)))))
          (when (plusp boxed) (yield-boxes))
          (physics-integrate-positions kernels world h)
          (when boxes (turn-box-rows boxes v h))
          (when joints
            (turn-jointed-orientations joints (physics-world-awake world) v h)
            (turn-joint-levers joints (physics-world-awake world)))
          (dotimes (k relaxes)
            (when boxes (setf (box-set-elapsed boxes) (+ elapsed h)) (solve-box-points boxes v d inv-h nil))
            (physics-solve-contacts kernels world inv-h nil (+ elapsed h))
            (when (plusp boxed) (yield-boxes)))
          ;; the joints' second relax, over the joints alone ([[#J0STIF]])
          (when joints (relax-joints joints v d inv-h kernels)))
        (when held (hold-crowded-speeds world))
        (when squeezed (hold-row-speeds world (physics-world-squeezed world) 1 squeezed))))
    ;; the box points that struck bounce once, after the substeps ([[#BXSOLV]])
    (when boxes
      (bounce-box-points boxes v)
      ;; the manifolds' friction into their points, for the next step ([[#BXSOLV]])
      (store-box-manifold-impulses boxes)))
    ;; the joints' colouring serves these substeps only: a pass run by hand solves contacts alone
    (when joints (setf (joint-set-solving joints) nil))
    world))

(defparameter *physics-phases*
  '(reset-phase wake-phase grid-phase pair-phase terrain-phase box-phase prune-phase
    prepare-phase substep-phase store-phase finalize-phase)
  "The phases of a step, in order; each is a function of the world. #IDVK7G")

(defun step-physics-world (world &optional dt)
  "Advance WORLD by DT seconds (its step length by default) through *physics-phases* and return
it. The step's events stay readable until the next step begins; the world's event handler, then
its step hook, when set, are called after the phases, while the step's boxes are still posted. #IDVK7G"
  (check-idle world 'step-physics-world)
  (let* ((dt (if dt (finite-f32 :dt dt world) (physics-world-step-seconds world)))
         (terrain (physics-world-terrain world))
         (started (clock-ns)))
    (unless (and (<= +physics-min-step-seconds+ dt) (< dt 1.0))
      (error 'invalid-physics-parameter :world world :name :dt :value dt
                                        :expected (format nil "from ~A to under 1 second" +physics-min-step-seconds+)))
    (setf (physics-world-current-dt world) dt
          (physics-world-current-h world) (/ dt (float (physics-world-substeps world) 1.0))
          (physics-world-stepping world) t)
    (open-step-undo world)
    (when terrain (lock-terrain terrain))
    (unwind-protect
         (progn
           (sb-int:with-float-traps-masked (:inexact :underflow)
             (run-physics-phases world))
           (setf (physics-world-undo-open world) nil)
           ;; the lasting sensors look at the bodies where the step left them ([[#S3NS0R]])
           (when (physics-world-sensors world)
             (sb-int:with-float-traps-masked (:inexact :underflow) (sense-phase world)))
           ;; the forces applied for this step are spent ([[#F0RC3S]])
           (when (physics-world-pushed world) (clear-physics-forces world))
           (let ((stats (world-statistics world)))
             (setf (step-statistics-contacts stats) (contact-columns-length (physics-world-contacts world))
                   (step-statistics-real-seconds stats) (* 1d-9 (coerce (the fixnum (- (clock-ns) started)) 'double-float))))
           (let ((handler (physics-world-event-handler world)))
             (when handler (map-physics-events handler world)))
           (let ((hook (physics-world-step-hook world)))
             (when hook (funcall hook world))))
      ;; the phases signalled before the store phase committed the step: undo it
      (when (physics-world-undo-open world) (roll-back-step world))
      (when terrain (unlock-terrain terrain))
      (box-columns-clear (physics-world-boxes world))
      (fill (physics-world-box-owners world) nil)
      (setf (physics-world-stepping world) nil))
    world))

(defun open-step-undo (world)
  "Start WORLD's undo log for the step about to run: no wakes, no sort, its step count and
statistics as they are. #IDVK7G"
  (setf (physics-world-undo-open world) t
        (physics-world-undo-woken-count world) 0
        (physics-world-undo-sorted world) nil
        (physics-world-undo-step-count world) (physics-world-step-count world))
  (copy-step-statistics-into (world-statistics world) (physics-world-undo-statistics world))
  world)

(defun unwake-last-body (world row)
  "Return the last awake body, woken this step from sleeping ROW, to that row, and the body that
took ROW when it left back to the end of the sleeping set: relocate-body run backwards. The body
is noted as a fresh sleeper, for waking took it out of the sleeping grids. #IDVK7G"
  (let* ((ids (physics-world-ids world))
         (awake (physics-world-awake world))
         (sleeping (physics-world-sleeping world))
         (last (1- (body-columns-length awake)))
         (end (body-columns-append sleeping)))
    (unless (= row end)
      (body-columns-copy-row sleeping row sleeping end)
      (setf (aref (handle-table-local ids) (handle-index (aref (body-columns-handle sleeping) end))) end))
    (body-columns-copy-row awake last sleeping row)
    ;; a sleeper's count of stillness is zero (sleep-physics-body)
    (setf (aref (body-columns-sleep-time sleeping) row) 0.0)
    (let ((handle (aref (body-columns-handle sleeping) row)))
      (setf (aref (handle-table-set ids) (handle-index handle)) +set-sleeping+
            (aref (handle-table-local ids) (handle-index handle)) row)
      (note-fresh-sleeper world handle))
    (body-columns-swap-remove awake last)
    world))

(defun roll-back-step (world)
  "Undo what a step that signalled before its store phase did to WORLD: put the awake rows back
in the order they had, send the bodies it woke back to their sleeping rows (last woken first),
and restore the step count and statistics. The step's events are dropped, and the pair list and
grids are rebuilt by the next step. #IDVK7G"
  (let* ((awake (physics-world-awake world))
         (locals (handle-table-local (physics-world-ids world)))
         (n (physics-world-undo-sorted world)))
    (when n
      (body-columns-permute awake (physics-world-awake-scratch world) (physics-world-undo-rows world) n)
      (let ((handle (body-columns-handle awake)))
        (dotimes (i n) (setf (aref locals (handle-index (aref handle i))) i))))
    (loop for k from (1- (physics-world-undo-woken-count world)) downto 0
          do (unwake-last-body world (aref (physics-world-undo-woken world) k)))
    ;; contacts the attempt stamped seen count as seen by the step before, so the next step
    ;; prunes every one it does not find again
    (let ((seen (contact-columns-seen (physics-world-contacts world)))
          (attempt (physics-world-step-count world)) (before (physics-world-undo-step-count world)))
      (dotimes (row (contact-columns-length (physics-world-contacts world)))
        (when (= (aref seen row) attempt) (setf (aref seen row) before))))
    (setf (physics-world-step-count world) (physics-world-undo-step-count world)
          (physics-world-undo-open world) nil
          (pair-list-rows (physics-world-pair-list world)) -1
          (physics-world-awake-grid-step world) -1
          (physics-world-sleeping-grid-dirty world) t)
    (copy-step-statistics-into (physics-world-undo-statistics world) (world-statistics world))
    (event-columns-clear (physics-world-events world))
    (fill (physics-world-event-data world) nil)
    world))

(defun run-physics-phases (world)
  "Run each phase of WORLD's step (*physics-phases*, less what its features leave out: see
world-phases) on WORLD, in order; when the world's phase clock is on (a
fixnum array of twice as many entries as phases), add each phase's nanoseconds to it under the
phase's position, and the bytes it consed under that position plus the number of phases. #IDVK7G"
  (let* ((clock (physics-world-phase-clock world)) (i 0)
         (phases (if clock (floor (length clock) 2) 0)))
    (declare (type (or null fixnum-column) clock) (type fixnum i phases))
    (dolist (phase (world-phases world))
      (let* ((start (if clock (clock-ns) 0))
             (consed (if clock (sb-ext:get-bytes-consed) 0)))
        ;; a phase the world's features leave out is NIL, and takes its place empty
        (when phase (funcall phase world))
        (when (and clock (< i phases))
          (incf (aref clock i) (- (clock-ns) start))
          (incf (aref clock (+ i phases)) (- (sb-ext:get-bytes-consed) consed)))
        (incf i))))
  world)

(defun physics-world-last-step-contact-count (world)
  "How many contacts the last step solved. #IDVK7G"
  (check-world world 'physics-world-last-step-contact-count)
  (step-statistics-contacts (world-statistics world)))

(defun physics-world-last-step-color-count (world)
  "How many colours the last step's contacts used, overflow included. #IDVK7G"
  (check-world world 'physics-world-last-step-color-count)
  (step-statistics-colors (world-statistics world)))

(defun physics-world-last-step-real-seconds (world)
  "Wall-clock seconds the last step took. #IDVK7G"
  (check-world world 'physics-world-last-step-real-seconds)
  (step-statistics-real-seconds (world-statistics world)))

(defun physics-world-max-approach-speed (world)
  "The fastest approach speed, m/s, of an overlapping contact at the end of the last step. #IDVK7G"
  (check-world world 'physics-world-max-approach-speed)
  (step-statistics-max-approach (world-statistics world)))
;; The step as built:1 ends here

;; [[file:../physics.org::#FEAT5X][Features: a world pays only for what it uses:1]]
(define-condition physics-feature-omitted (physics-error)
  ((feature :initarg :feature :reader physics-feature-omitted-feature)
   (operation :initarg :operation :reader physics-feature-omitted-operation))
  (:report (lambda (c s)
             (format s "~(~A~) needs the feature ~S, which this world was made without (see its ~
                        :features)" (physics-feature-omitted-operation c) (physics-feature-omitted-feature c))))
  (:documentation "An operation that needs a feature the world's feature set leaves out. #FEAT5X"))

(defparameter +event-features+
  '((:contact-events 0 1 7) (:hit-events 2) (:sleep-events 3 4) (:expiry-events 5 6))
  "Each event feature and the event codes it records. #FEAT5X")

(defun checked-physics-features (features sleep)
  "FEATURES (a list of keywords of +physics-features+, :events for every event kind) as a set in
the order of +physics-features+, less :sleep and :sleep-events when SLEEP is false; the set of
every feature is +physics-features+ itself. #FEAT5X"
  (unless (and (listp features)
               (every (lambda (f) (or (eq f :events) (member f +physics-features+))) features))
    (error 'invalid-physics-parameter :name :features :value features
                                      :expected (format nil "a list of ~{~S~^ ~} or :events" +physics-features+)))
  (let* ((given (if (member :events features) (append (mapcar #'first +event-features+) features) features))
         (set (remove-if-not (lambda (f) (and (member f given) (or sleep (not (member f '(:sleep :sleep-events))))))
                             +physics-features+)))
    (if (equal set +physics-features+) +physics-features+ set)))

(defun constraint-block-floats (features)
  "The floats of a main block of eight constraints in a world of FEATURES: the columns of
+constraint-columns+ up to the last one a kernel of FEATURES reads. #FEAT5X"
  (+ 8 (constraint-offset (cond ((member :restitution features) 'restitution)
                                ((member :rolling-resistance features) 'rolling-impulse-z)
                                ((intersection '(:contact-events :hit-events) features) 'relative-velocity)
                                ((member :boxes features) 'kvt2)
                                (t 'gap)))))

(defun constraint-side-floats (features)
  "The floats of a side block of eight constraints in a world of FEATURES: the columns of
+constraint-side-columns+ up to the last one a kernel of FEATURES reads, none without friction
and restitution. #FEAT5X"
  (cond ((member :restitution features) (+ 8 (constraint-offset 'armed-speed)))
        ((member :friction features) (+ 8 (constraint-offset 'spin-impulse)))
        (t 0)))

(defun feature-event-mask (features)
  "The event codes FEATURES record, as bits of a fixnum. #FEAT5X"
  (loop for (feature . codes) in +event-features+
        when (member feature features)
          sum (loop for code in codes sum (ash 1 code))))

(defun physics-world-features (world)
  "The features WORLD may use, a list of keywords of +physics-features+. #FEAT5X"
  (check-world world 'physics-world-features)
  (copy-list (world-features world)))

(defun require-physics-feature (world feature operation)
  "Signal physics-feature-omitted, naming FEATURE and OPERATION, unless WORLD has FEATURE. #FEAT5X"
  (unless (member feature (world-features world))
    (error 'physics-feature-omitted :world world :feature feature :operation operation)))

(defun set-physics-body-material (world handle &key restitution friction rolling-resistance)
  "Set the restitution, friction and rolling resistance of HANDLE's body, each only when given,
and wake the body, so that its contacts take them from the next step on: all of them or, when
one is out of range or needs a feature WORLD was made without (physics-feature-omitted), none,
and the body is not woken. #FEAT5X"
  (check-idle world 'set-physics-body-material)
  (resolve-handle world handle)
  (multiple-value-bind (e mu rho)
      (checked-material world 'set-physics-body-material restitution friction rolling-resistance)
    (let ((row (wake-handle world handle)) (awake (physics-world-awake world)))
      (with-body-columns ((restitution-c restitution) (friction-c friction)
                          (rolling-resistance-c rolling-resistance))
          awake
        (when e (setf (aref restitution-c row) e))
        (when mu (setf (aref friction-c row) mu))
        (when rho (setf (aref rolling-resistance-c row) rho)))))
  (values))

(defun feature-phases (features phases)
  "PHASES, a list of phase names, with NIL in place of each phase FEATURES leave out (so a phase
keeps its place, where the phase clock counts it), the prepare, store and finalize phases
compiled for FEATURES, and quiet-wake-phase for the wake phase of a world without body contacts
and boxes. #FEAT5X"
  (flet ((has (f) (member f features)))
    (loop for phase in phases
          collect (unless (case phase
                            (wake-phase (not (has :sleep)))
                            (grid-phase (not (or (has :body-contacts) (has :boxes))))
                            (pair-phase (not (has :body-contacts)))
                            (terrain-phase (not (has :terrain)))
                            (box-phase (not (has :boxes))))
                    (cond ((member phase '(prepare-phase store-phase finalize-phase)) (featured-kernel phase features))
                          ;; nothing a step moves reaches a sleeper
                          ((and (eq phase 'wake-phase) (not (has :body-contacts)) (not (has :boxes))) 'quiet-wake-phase)
                          (t phase))))))

(defun world-phases (world)
  "The phases WORLD's step runs: *physics-phases* for a world of every feature, else those its
features keep, found once for each value of *physics-phases*. #FEAT5X"
  (let ((features (world-features world)))
    (cond ((eq features +physics-features+) *physics-phases*)
          ((eq (world-phases-source world) *physics-phases*) (world-phases-built world))
          (t (setf (world-phases-built world) (feature-phases features *physics-phases*)
                   (world-phases-source world) *physics-phases*)
             (world-phases-built world)))))

(defvar *featured-kernels* (make-hash-table :test 'equal)
  "The variants of featured kernels: (NAME . FEATURES) to the function compiled for FEATURES. #FEAT5X")

(defun featured-kernel (name features)
  "The kernel NAME for a world of FEATURES: NAME itself when FEATURES hold all it tests, else its
variant, compiled the first time it is asked for. #FEAT5X"
  (let ((key (kernel-feature-key name features)))
    (if (equal key (kernel-feature-key name +physics-features+))
        name
        (or (gethash (cons name key) *featured-kernels*)
            (setf (gethash (cons name key) *featured-kernels*)
                  ;; in the page's package, where the macros of the text intern their names
                  (let ((*package* (find-package '#:luv-physics)))
                    (funcall (compile nil `(lambda () ,(featured-kernel-form name key))))))))))

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +standard-feature-sets+
    '((:terrain :friction :sleep :mortal)
      (:terrain :body-contacts :friction :sleep))
    "The feature sets whose variants are compiled with the page: drops that meet only the
terrain, and a pile of balls with friction alone, neither recording events. #FEAT5X"))

(defmacro precompile-featured-kernels ((&rest names))
  "Compile, with the page, the variants of the kernels NAMES for +standard-feature-sets+, and
keep them where featured-kernel finds them. #FEAT5X"
  `(progn
     ,@(loop for name in names
             append (loop for key in (remove-duplicates
                                      (mapcar (lambda (set) (kernel-feature-key name set)) +standard-feature-sets+)
                                      :test #'equal)
                          unless (equal key (kernel-feature-key name +physics-features+))
                            collect `(setf (gethash '(,name . ,key) *featured-kernels*)
                                           ,(featured-kernel-form name key))))))

(precompile-featured-kernels (warm-start-range solve-range prepare-frames-range prepare-phase store-phase
                                              finalize-phase))

(defgeneric wide-kernel-names (kernels)
  (:documentation "The names of the featured warm start, solve and frame pass of the wide family
KERNELS, and of the solve's copy with the impact part, as four values, or NIL for a family
without wide kernels. #FEAT5X"))

(defmethod wide-kernel-names ((kernels scalar-kernels)) nil)

(defun world-kernel-variant (world kernels)
  "The kernels WORLD's features need in the family KERNELS, found once per family. #FEAT5X"
  (let ((variant (world-kernel-variant-built world)))
    (if (and variant (eq (kernel-variant-kernels variant) kernels))
        variant
        (let ((features (world-features world)))
          (multiple-value-bind (ws so pf) (wide-kernel-names kernels)
            (setf (world-kernel-variant-built world)
                  (make-kernel-variant kernels
                                       (featured-kernel 'warm-start-range features)
                                       (featured-kernel 'solve-range features)
                                       (featured-kernel 'prepare-frames-range features)
                                       (and ws (featured-kernel ws features))
                                       (and so (featured-kernel so features))
                                       (and pf (featured-kernel pf features)))))))))
;; Features: a world pays only for what it uses:1 ends here

;; [[file:../physics.org::#S6T2MV][Determinism is chosen: same code, same start, same hash:1]]
(defun physics-world-state-hash (world)
  "A 62-bit FNV-style hash of the bits of every body's position, velocity and angular
velocity, awake set first, each set in row order. Equal hashes mean bit-equal states. #S6T2MV"
  (check-world world 'physics-world-state-hash)
  (let ((hash 0))
    (declare (type (unsigned-byte 62) hash))
    (dolist (buffer (list (physics-world-awake world) (physics-world-sleeping world)))
      (with-body-columns (x y z vx vy vz wx wy wz) buffer
        (dotimes (i (body-columns-length buffer))
          (dolist (column (list x y z vx vy vz wx wy wz))
            (setf hash (ldb (byte 62 0)
                            (+ (* hash 1099511628211)
                               (ldb (byte 32 0) (sb-kernel:single-float-bits (aref column i))))))))))
    ;; a world of boxes hashes orientations and extents too ([[#BXR0WS]])
    (let ((boxes (physics-world-box-bodies world)))
      (when boxes
        (dolist (buffer (list (physics-world-awake world) (physics-world-sleeping world)))
          (with-body-columns (qw qx qy qz handle) buffer
            (dotimes (i (body-columns-length buffer))
              (let ((slot (handle-index (aref handle i))))
                (dolist (value (list* (aref qw i) (aref qx i) (aref qy i) (aref qz i)
                                      (if (< slot (length (box-set-hx boxes)))
                                          (list (aref (box-set-hx boxes) slot) (aref (box-set-hy boxes) slot)
                                                (aref (box-set-hz boxes) slot))
                                          (list 0.0 0.0 0.0))))
                  (setf hash (ldb (byte 62 0)
                                  (+ (* hash 1099511628211)
                                     (ldb (byte 32 0) (sb-kernel:single-float-bits value))))))))))))
    hash))
;; Determinism is chosen: same code, same start, same hash:1 ends here

;; [[file:../physics.org::#V4L1D8][The validation walker:1]]
(defun validate-physics-world (world)
  "Walk every forwarding address and contact key of WORLD; return T, or signal
physics-world-invalid naming the first broken invariant. #V4L1D8"
  (check-world world 'validate-physics-world)
  (flet ((fail (fmt &rest args)
           (error 'physics-world-invalid :world world :invariant (apply #'format nil fmt args))))
    (let* ((ids (physics-world-ids world))
           (sets (handle-table-set ids)) (locals (handle-table-local ids))
           (awake (physics-world-awake world))
           (seen (make-hash-table)))
      ;; every row's handle points back at that row
      (loop for (set buffer) in (list (list +set-awake+ awake)
                                      (list +set-sleeping+ (physics-world-sleeping world)))
            do (dotimes (row (body-columns-length buffer))
                 (let ((h (aref (body-columns-handle buffer) row)))
                   (when (handle-status ids h)
                     (fail "row ~D of set ~D holds handle ~D, which is ~(~A~)" row set h (handle-status ids h)))
                   (when (gethash h seen) (fail "handle ~D appears in two rows" h))
                   (setf (gethash h seen) t)
                   (unless (and (= (aref sets (handle-index h)) set) (= (aref locals (handle-index h)) row))
                     (fail "handle ~D forwards to set ~D row ~D but lives in set ~D row ~D"
                           h (aref sets (handle-index h)) (aref locals (handle-index h)) set row)))))
      ;; every live slot is some row's; free slots chain through the free list
      (let ((live 0) (free 0))
        (dotimes (slot (handle-table-count ids))
          (if (= (aref sets slot) +set-free+) (incf free) (incf live)))
        (unless (= live (hash-table-count seen))
          (fail "~D live handle slots but ~D body rows" live (hash-table-count seen)))
        (loop with slot = (handle-table-free ids) and steps = 0
              while (>= slot 0)
              do (unless (= (aref sets slot) +set-free+) (fail "free list reaches live slot ~D" slot))
                 (when (> (incf steps) free) (fail "the free list is longer than the ~D free slots" free))
                 (setf slot (aref locals slot))
              finally (unless (= steps free) (fail "the free list holds ~D of ~D free slots" steps free))))
      ;; the dummy row past the awake set is zero
      (let ((n (body-columns-length awake)))
        (dolist (column +body-columns-column-names+)
          (let ((value (aref (slot-value awake column) n)))
            (unless (zerop value) (fail "dummy row column ~A is ~S, not zero" column value)))))
      ;; every contact row is in the table under its key, and nothing else is
      (let ((contacts (physics-world-contacts world)) (table (physics-world-contact-table world)))
        (dotimes (row (contact-columns-length contacts))
          (let ((found (contact-table-find table (aref (contact-columns-key contacts) row))))
            (unless (= found row)
              (fail "contact row ~D's key maps to row ~D" row found))))
        (unless (= (contact-table-count table) (contact-columns-length contacts))
          (fail "contact table holds ~D keys for ~D contacts"
                (contact-table-count table) (contact-columns-length contacts))))
      (unless (>= (body-columns-capacity awake) (body-columns-length awake))
        (fail "awake capacity below its length"))
      ;; the count of mortal sleepers, which decides whether finalize ages the sleepers
      (let* ((sleeping (physics-world-sleeping world))
             (mortal (count-if #'plusp (body-columns-life sleeping) :end (body-columns-length sleeping))))
        (unless (= mortal (physics-world-mortal-sleepers world))
          (fail "~D mortal sleepers counted as ~D" mortal (physics-world-mortal-sleepers world))))
      ;; the box set agrees with the box rows ([[#BXR0WS]])
      (validate-box-set world #'fail)
      ;; the forces and gravity scales ([[#F0RC3S]]) cover every slot, a free slot holds neither,
      ;; no force waits unless one was applied, and the scales other than 1 are counted
      (let ((pushes (physics-world-pushes world)) (scaled 0))
        (when pushes
          (unless (>= (length pushes) (* 4 (handle-table-count ids)))
            (fail "the pushes cover ~D of ~D handle slots" (floor (length pushes) 4) (handle-table-count ids)))
          (dotimes (slot (floor (length pushes) 4))
            (let* ((p (* 4 slot))
                   (forced (notevery #'zerop (subseq pushes p (+ p 3)))))
              (when (/= 1.0 (aref pushes (+ p 3))) (incf scaled))
              (when (and (or (>= slot (handle-table-count ids)) (= (aref sets slot) +set-free+))
                         (or forced (/= 1.0 (aref pushes (+ p 3)))))
                (fail "free handle slot ~D holds a force or a gravity scale" slot))
              (when (and forced (not (physics-world-pushed world)))
                (fail "handle slot ~D holds a force no call applied" slot)))))
        (unless (= scaled (physics-world-scaled-count world))
          (fail "~D gravity scales other than 1 counted as ~D" scaled (physics-world-scaled-count world))))
      ;; the joints ([[#J0STOR]])
      (validate-joints world #'fail)
      t)))
;; The validation walker:1 ends here

;; [[file:../physics.org::#B0DY0B][A body as an object:1]]
(defclass physics-body ()
  ((world :initarg :world :reader physics-body-world)
   (handle :initarg :handle :reader physics-body-handle))
  (:documentation "A body as an object: a world and a handle. Its numbers live in the world's
columns; describe shows that row as if it were slots. #B0DY0B"))

(setf (documentation 'physics-body-world 'function) "The world of the physics-body BODY. #B0DY0B"
      (documentation 'physics-body-handle 'function) "The handle of the physics-body BODY. #B0DY0B")

(defun physics-body (world handle)
  "The physics-body object for HANDLE in WORLD. #B0DY0B"
  (check-world world 'physics-body)
  (resolve-handle world handle)
  (make-instance 'physics-body :world world :handle handle))

(defmethod print-object ((body physics-body) stream)
  (print-unreadable-object (body stream :type t)
    (let ((w (physics-body-world body)) (h (physics-body-handle body)))
      (if (physics-body-alive-p w h)
          (multiple-value-bind (x y z) (physics-body-position w h)
            (format stream "~D ~:[asleep~;awake~] at (~,3F ~,3F ~,3F)" (handle-index h)
                    (physics-body-awake-p w h) x y z))
          (format stream "~D removed" (handle-index h))))))

(defun body-summary (body)
  "BODY's row as (LABEL TEXT VALUE) lines: position, velocity, angular velocity, radius, mass,
material, awake, kind. #B0DY0B"
  (let ((w (physics-body-world body)) (h (physics-body-handle body)))
    (multiple-value-bind (set row) (resolve-handle w h)
      (with-body-columns (restitution friction rolling-resistance inverse-mass) (set-buffer w set)
        (flet ((triple (reader) (multiple-value-list (funcall reader w h))))
          (let ((position (triple #'physics-body-position))
                (velocity (triple #'physics-body-velocity))
                (spin (triple #'physics-body-angular-velocity))
                (radius (physics-body-radius w h))
                (mass (/ 1.0 (aref inverse-mass row)))
                (material (list (aref restitution row) (aref friction row) (aref rolling-resistance row)))
                (awake (= set +set-awake+))
                (kind (physics-body-kind w h)))
            (list (list "position" (format nil "~{~,4F~^ ~} m" position) position)
                  (list "velocity" (format nil "~{~,4F~^ ~} m/s" velocity) velocity)
                  (list "angular velocity" (format nil "~{~,4F~^ ~} rad/s" spin) spin)
                  (list "radius" (format nil "~A m" radius) radius)
                  (list "mass" (format nil "~A kg" mass) mass)
                  (list "material" (format nil "restitution ~A, friction ~A, rolling resistance ~A"
                                           (first material) (second material) (third material))
                        material)
                  (list "awake" (if awake "yes" "no, asleep") awake)
                  (list "kind" (format nil "~D~@[ ~(~S~)~]" kind (physics-body-kind-name w h)) kind))))))))

(defmethod describe-object ((body physics-body) stream)
  (let ((w (physics-body-world body)) (h (physics-body-handle body)))
    (format stream "~&~S~%  handle ~D (slot ~D, generation ~D) of ~S~%" body h (handle-index h)
            (handle-generation h) w)
    (when (physics-body-alive-p w h)
      (loop for (label text) in (body-summary body)
            do (format stream "  ~18A ~A~%" label text))
      (multiple-value-bind (set row) (resolve-handle w h)
        (format stream "  Its row, ~:[sleeping~;awake~] set row ~D:~%" (= set +set-awake+) row)
        (let ((buffer (set-buffer w set)))
          (dolist (column +body-columns-column-names+)
            (format stream "  ~(~22A~) = ~S~%" column (aref (slot-value buffer column) row))))))))
;; A body as an object:1 ends here

;; [[file:../physics.org::#4YDMX5][A world as an object, and both in the inspector:1]]
(defun kernel-family-name (kernels)
  "The name under which the kernel family object KERNELS is registered, or its class name. #4YDMX5"
  (let ((class (class-name (class-of kernels))))
    (or (car (find class *kernel-families* :key #'second)) class)))

(defmethod print-object ((world physics-world) stream)
  (if (slot-boundp world 'kernels)
      (print-unreadable-object (world stream :type t)
        (let ((awake (physics-world-awake-count world)))
          (format stream "~D bod~:@P (~D awake) step ~D ~(~A~)"
                  (+ awake (physics-world-sleeping-count world)) awake
                  (physics-world-step-count world) (kernel-family-name (physics-world-kernels world)))))
      (print-unreadable-object (world stream :type t :identity t))))

(defun world-summary (world)
  "WORLD's settings and last step, as (LABEL TEXT) lines for describe and the inspector. #4YDMX5"
  (flet ((line (label format-control &rest arguments)
           (list label (apply #'format nil format-control arguments))))
    (list (line "step" "~,4F s in ~D substeps, gravity (~,2F ~,2F ~,2F) m/s^2, sleep ~:[off~;on~]"
                (physics-world-step-seconds world) (physics-world-substeps world)
                (physics-world-gravity-x world) (physics-world-gravity-y world) (physics-world-gravity-z world)
                (physics-world-sleep-enabled world))
          (line "terrain" "~:[none~;~:*~D chunk~:P of 16^3 cells~]"
                (let ((terrain (physics-world-terrain world)))
                  (and terrain (hash-table-count (voxel-terrain-chunks terrain)))))
          (line "last step" "~D contacts in ~D colours (~D overflowing), ~,6F s"
                (physics-world-last-step-contact-count world) (physics-world-last-step-color-count world)
                (physics-world-overflow-count world) (physics-world-last-step-real-seconds world))
          (line "left" "deepest overlap ~,4F m, fastest approach ~,3F m/s"
                (physics-world-max-penetration world) (physics-world-max-approach-speed world))
          (line "contacts" "~A Hz, damping ratio ~A, push-out ~A m/s, slop ~A m, margin ~A m, pair skin ~A m"
                (physics-world-contact-hertz world) (physics-world-damping-ratio world)
                (physics-world-push-max world) (physics-world-slop world) (physics-world-margin world)
                (physics-world-pair-skin world))
          (line "speeds" "bounce above ~A m/s, hit above ~A m/s, still under ~A m/s for ~A s, wake above ~A m/s"
                (physics-world-restitution-threshold world) (physics-world-hit-speed world)
                (physics-world-sleep-speed world) (physics-world-time-to-sleep world)
                (physics-world-wake-speed world))
          (line "events" "~:[no handler~;handler ~:*~S~]" (physics-world-event-handler world))
          (line "joints" "~D joint~:P, ~D solved in the last step" (physics-world-joint-count world)
                (let ((set (physics-world-joints world)))
                  (if set (count-if-not #'minusp (joint-columns-row-a (joint-set-rows set))
                                        :end (joint-columns-length (joint-set-rows set)))
                      0))))))

(defmethod describe-object ((world physics-world) stream)
  (format stream "~&~S~%" world)
  (loop for (label text) in (world-summary world)
        do (format stream "  ~10A ~A~%" label text)))

(defun inspection-parts (object)
  "The SLIME inspector's content for OBJECT, a physics-world or a physics-body, in SWANK's format. #4YDMX5"
  (etypecase object
    (physics-world
     (append (list (prin1-to-string object) '(:newline))
             (loop for (label . value) in (world-inspected-parts object)
                   append (list (format nil "~10A " label)
                                (if (stringp value) value (list :value value))
                                '(:newline)))))
    (physics-body
     (let ((world (physics-body-world object)))
       (append (list (prin1-to-string object) '(:newline) "world      " (list :value world) '(:newline))
               (loop for (label text value) in (body-summary object)
                     append (list (format nil "~18A " label) (list :value value text) '(:newline))))))))

(defun install-swank-inspection ()
  "If SWANK is loaded, make its inspector show worlds and bodies by inspection-parts; true if it did. #4YDMX5"
  (let ((inspect (and (find-package "SWANK") (find-symbol "EMACS-INSPECT" "SWANK"))))
    (when (and inspect (fboundp inspect))
      (dolist (class '(physics-world physics-body) t)
        (eval `(defmethod ,inspect ((object ,class)) (inspection-parts object)))))))

(install-swank-inspection)
;; A world as an object, and both in the inspector:1 ends here

;; [[file:../physics.org::#H4NDL3][A handle explained, and a world opened part by part:1]]
(defun world-contacts-list (world)
  "WORLD's contact rows as property lists: :kind (:pair, :cell or :box), :a and :b (handles; :b
is nil but for a pair), :normal, :separation, :point, :normal-impulse and :touching. Made for
a person; the step never calls it. #H4NDL3"
  (let ((c (physics-world-contacts world)))
    (loop with geometry = (contact-columns-geometry c)
          for row below (contact-columns-length c)
          for b = (aref (contact-columns-handle-b c) row)
          collect (list :kind (svref #(:pair :cell :box) (aref (contact-columns-kind c) row))
                        :a (aref (contact-columns-handle-a c) row)
                        :b (if (= b +no-body+) nil b)
                        :normal (list (contact@ geometry row nx) (contact@ geometry row ny)
                                      (contact@ geometry row nz))
                        :separation (contact@ geometry row separation)
                        :point (list (contact@ geometry row px) (contact@ geometry row py)
                                     (contact@ geometry row pz))
                        :normal-impulse (contact@ geometry row normal-impulse)
                        :touching (/= 0 (aref (contact-columns-touching c) row))))))

(defun world-parameters-list (world)
  "WORLD's step and contact parameters as a property list keyed as make-physics-world's
arguments are. #H4NDL3"
  (list :step-seconds (physics-world-step-seconds world) :substeps (physics-world-substeps world)
        :gravity (list (physics-world-gravity-x world) (physics-world-gravity-y world)
                       (physics-world-gravity-z world))
        :sleep (physics-world-sleep-enabled world)
        :contact-hertz (physics-world-contact-hertz world)
        :damping-ratio (physics-world-damping-ratio world)
        :push-max (physics-world-push-max world) :slop (physics-world-slop world)
        :margin (physics-world-margin world) :pair-skin (physics-world-pair-skin world)
        :restitution-threshold (physics-world-restitution-threshold world)
        :hit-speed (physics-world-hit-speed world) :sleep-speed (physics-world-sleep-speed world)
        :time-to-sleep (physics-world-time-to-sleep world) :wake-speed (physics-world-wake-speed world)
        :features (physics-world-features world)))

(defun world-inspected-parts (world)
  "WORLD's parts for a person, as (LABEL . VALUE): the summary's lines as text, then its bodies
as physics-body objects, its contacts (world-contacts-list), its parameters, its terrain and its
kernel family. #H4NDL3"
  (append (loop for (label text) in (world-summary world) collect (cons label text))
          (list (cons "bodies" (loop for h in (physics-world-handles world)
                                     collect (physics-body world h)))
                (cons "contact rows" (world-contacts-list world))
                (cons "joint rows" (physics-world-joint-objects world))
                (cons "parameters" (world-parameters-list world))
                (cons "terrain" (physics-world-terrain world))
                (cons "kernels" (physics-world-kernels world)))))

(defmethod print-object ((terrain voxel-terrain) stream)
  (print-unreadable-object (terrain stream :type t)
    (format stream "~D chunk~:P resident, ~D edit~:P"
            (hash-table-count (voxel-terrain-chunks terrain)) (voxel-terrain-edits terrain))))

(defmethod sb-impl::inspected-parts ((world physics-world))
  (values (format nil "~S~%" world) t (world-inspected-parts world)))

(defmethod sb-impl::inspected-parts ((body physics-body))
  (values (format nil "~S~%" body) t
          (cons (cons "world" (physics-body-world body))
                (loop for (label nil value) in (and (physics-body-alive-p (physics-body-world body)
                                                                          (physics-body-handle body))
                                                    (body-summary body))
                      collect (cons label value)))))

(defmethod sb-impl::inspected-parts ((terrain voxel-terrain))
  (values (format nil "~S~%" terrain) t
          (list (cons "chunks resident" (hash-table-count (voxel-terrain-chunks terrain)))
                (cons "chunk budget" (voxel-terrain-budget terrain))
                (cons "edits" (voxel-terrain-edits terrain))
                (cons "chunks" (voxel-terrain-chunks terrain)))))
;; A handle explained, and a world opened part by part:1 ends here

;; [[file:../physics.org::#W0RKP1][Workers are threads made once, parked between steps:1]]
(defconstant +physics-max-workers+ 64
  "The most workers a world may have. #W0RKP1")

(defconstant +worker-spins+ 500
  "How many turns of the pause instruction a waiting worker or caller spins before it yields its
core. #W0RKP1")

(defconstant +worker-park-spins+ 20000
  "How many times, at most, a worker waiting for a job spins or yields before it parks. #W0RKP1")

(defconstant +worker-park-ns+ 500000
  "How long, in nanoseconds, a worker waiting for a job spins or yields at most before it parks:
the jobs of a step follow each other within it, the gap between a game's frames does not. #W0RKP1")

(defconstant +pool-jobs+ 20
  "How many kinds of job a pool keeps its calls and timings for ([[#SPL1T5]]). #W0RKP1")

(defstruct (worker-pool (:constructor %make-worker-pool (count)) (:copier nil))
  "The threads of a world with workers, and the job they share: its stages and parameters, in
typed slots so that publishing a job conses nothing. #W0RKP1"
  (count 1 :type (integer 1 64) :read-only t)
  (threads '() :type list)
  (generation 0 :type sb-ext:word)
  (parked 0 :type sb-ext:word)
  (finished 0 :type sb-ext:word)
  (arrived 0 :type sb-ext:word)
  (sense 0 :type sb-ext:word)
  (mutex (sb-thread:make-mutex :name "luv-physics workers") :read-only t)
  (wakeup (sb-thread:make-waitqueue :name "luv-physics workers") :read-only t)
  (closing nil)
  (modes 0 :type (unsigned-byte 32))
  (failure nil)
  (failure-stage most-positive-fixnum :type fixnum)
  (failure-worker 0 :type fixnum)
  ;; the job: which one, and how many stages
  (job 0 :type fixnum)
  (stages 0 :type fixnum)
  ;; a pass splits only over at least this many rows; below it worker 0 runs it all
  (split-rows 4096 :type index)
  ;; how many times a worker waiting for a job spins or yields before it parks
  (park-spins +worker-park-spins+ :type fixnum)
  ;; a colour splits only when it has at least this many rows per worker ([[#SPL1T5]])
  (share-rows 64 :type index)
  ;; per job: its calls, and the nanoseconds per 1024 rows it took split and whole ([[#SPL1T5]])
  (calls (make-array +pool-jobs+ :element-type 'fixnum :initial-element 0) :type fixnum-column :read-only t)
  (split-ns (make-array +pool-jobs+ :element-type 'fixnum :initial-element 0) :type fixnum-column :read-only t)
  (whole-ns (make-array +pool-jobs+ :element-type 'fixnum :initial-element 0) :type fixnum-column :read-only t)
  ;; per job: the nanoseconds all its calls took, either way ([[#B3NCHW]] reads them)
  (spent (make-array +pool-jobs+ :element-type 'fixnum :initial-element 0) :type fixnum-column :read-only t)
  ;; per job: the part of spent its merges took on the calling thread alone ([[#P41P1C]])
  (merged (make-array +pool-jobs+ :element-type 'fixnum :initial-element 0) :type fixnum-column :read-only t)
  ;; per job: how many of its tuned calls ran split ([[#B3NCHW]])
  (splits (make-array +pool-jobs+ :element-type 'fixnum :initial-element 0) :type fixnum-column :read-only t)
  ;; a phase's own piece, a function of the worker and the count, while its job runs
  (piece nil :type (or null function))
  ;; the events of a phase's pieces, a buffer and its data for each worker but worker 0,
  ;; merged in worker order ([[#SPL1T5]])
  (events #() :type simple-vector)
  (event-data #() :type simple-vector)
  ;; each worker's pair sink: the pairs and touches its piece of the pair phase found ([[#P41P1C]])
  (pair-sinks #() :type simple-vector)
  ;; the parameters of the job, written by the caller before it publishes
  (wide nil) (narrow nil) (impact nil) (settle nil)
  (lanes 1 :type (integer 1 64))
  (cbuf nil)
  ;; the joint set whose joints a colour pass solves with its contacts, or NIL ([[#J0FAML]])
  (joints nil)
  (v (make-array 0 :element-type 'single-float) :type f32-column)
  (d (make-array 0 :element-type 'single-float) :type f32-column)
  (pushes (make-array 0 :element-type 'single-float) :type f32-column)
  (handles (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (masses (make-array 0 :element-type 'single-float) :type f32-column)
  (starts (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (stage-colours (make-array (+ +physics-max-colors+ 1) :element-type 'fixnum :initial-element 0)
   :type fixnum-column :read-only t)
  (rows 0 :type index)
  (h 0.0 :type single-float) (inv-h 0.0 :type single-float) (use-bias nil)
  (elapsed 0.0 :type single-float) (push-max 0.0 :type single-float)
  (threshold 0.0 :type single-float)
  (hgx 0.0 :type single-float) (hgy 0.0 :type single-float) (hgz 0.0 :type single-float)
  (gx 0.0 :type single-float) (gy 0.0 :type single-float) (gz 0.0 :type single-float)
  (max-speed 0.0 :type single-float))

(defun machine-cores ()
  "The number of cores this machine has online (sysconf), at least 1. #W0RKP1"
  (max 1 (sb-alien:alien-funcall
          (sb-alien:extern-alien "sysconf" (function sb-alien:long sb-alien:int))
          84)))                           ; _SC_NPROCESSORS_ONLN

(defun checked-worker-count (workers)
  "The worker count WORKERS names: itself, from 1 to +physics-max-workers+, or for :auto the
machine's cores; else invalid-physics-parameter naming :workers. #W0RKP1"
  (cond ((eq workers :auto) (min +physics-max-workers+ (machine-cores)))
        ((and (integerp workers) (<= 1 workers +physics-max-workers+)) workers)
        (t (error 'invalid-physics-parameter
                  :name :workers :value workers
                  :expected (format nil "an integer from 1 to ~D, or :auto, in make-physics-world"
                                    +physics-max-workers+)))))

(defun spin-or-yield (spins)
  "Wait a moment, the SPINSth time a loop has waited: a pause while SPINS is below
+worker-spins+, else give up the core. Return SPINS plus one. #W0RKP1"
  (declare (type fixnum spins))
  (if (< spins +worker-spins+) (sb-ext:spin-loop-hint) (sb-thread:thread-yield))
  (1+ spins))

(defun await-generation (pool seen)
  "Wait until POOL's generation differs from SEEN, spinning, then parked on its wait queue;
return the new generation. #W0RKP1"
  (declare (type worker-pool pool) (type sb-ext:word seen))
  (let ((spins 0) (start (clock-ns)))
    (declare (type fixnum spins start))
    (loop while (and (< spins (worker-pool-park-spins pool))
                     ;; past the pauses, the clock is read every 64th turn
                     (or (< spins +worker-spins+) (logtest spins 63)
                         (< (- (clock-ns) start) +worker-park-ns+)))
          do (unless (= (worker-pool-generation pool) seen)
               (return-from await-generation (worker-pool-generation pool)))
             (setf spins (spin-or-yield spins))))
  (sb-thread:with-mutex ((worker-pool-mutex pool))
    (sb-ext:atomic-incf (worker-pool-parked pool))
    (loop while (= (worker-pool-generation pool) seen)
          do (sb-thread:condition-wait (worker-pool-wakeup pool) (worker-pool-mutex pool)))
    (sb-ext:atomic-decf (worker-pool-parked pool))
    (worker-pool-generation pool)))

(defun await-workers (pool)
  "The barrier between two stages of POOL's job: return once every worker has arrived. #W0RKP1"
  (declare (type worker-pool pool))
  (let ((sense (worker-pool-sense pool)))
    (if (= (sb-ext:atomic-incf (worker-pool-arrived pool)) (1- (worker-pool-count pool)))
        (progn (setf (worker-pool-arrived pool) 0)
               (sb-ext:atomic-incf (worker-pool-sense pool)))
        (let ((spins 0))
          (declare (type fixnum spins))
          (loop while (= (worker-pool-sense pool) sense)
                do (setf spins (spin-or-yield spins))))))
  pool)

(defun note-worker-failure (pool worker stage condition)
  "Keep CONDITION, signalled in WORKER's piece of STAGE, when no earlier stage or lower worker of
it has failed. #W0RKP1"
  (sb-thread:with-mutex ((worker-pool-mutex pool))
    (when (or (< stage (worker-pool-failure-stage pool))
              (and (= stage (worker-pool-failure-stage pool)) (< worker (worker-pool-failure-worker pool))))
      (setf (worker-pool-failure pool) condition
            (worker-pool-failure-stage pool) stage
            (worker-pool-failure-worker pool) worker))))

(defun run-worker-stages (pool worker)
  "Run WORKER's piece of every stage of POOL's job, with the barrier between stages; a piece
that signals is kept (note-worker-failure) and the stages after it are skipped. #W0RKP1"
  (declare (type worker-pool pool) (type fixnum worker))
  (let ((stages (worker-pool-stages pool)))
    (dotimes (stage stages)
      (when (> (worker-pool-failure-stage pool) (1- stage))
        (handler-case (run-worker-stage pool worker stage)
          (serious-condition (c) (note-worker-failure pool worker stage c))))
      (when (< (1+ stage) stages) (await-workers pool)))))

(defun worker-loop (pool worker)
  "The life of WORKER, a thread of POOL: wait for a job, run its pieces, count itself
finished; until the pool closes. #W0RKP1"
  (declare (type worker-pool pool) (type fixnum worker))
  ;; a new pool's generation is 0: a thread that starts late still sees the first job
  (let ((seen 0))
    (declare (type sb-ext:word seen))
    (loop
      (setf seen (await-generation pool seen))
      (when (worker-pool-closing pool) (return))
      (setf (sb-vm:floating-point-modes) (worker-pool-modes pool))
      (run-worker-stages pool worker)
      (sb-ext:atomic-incf (worker-pool-finished pool)))))

(defun run-on-workers (pool job stages)
  "Run JOB, of STAGES stages, on every worker of POOL, the calling thread as worker 0, whose
parameters the caller has written into POOL; return once all have finished, or signal the
condition of the earliest piece that signalled. #W0RKP1"
  (declare (type worker-pool pool) (type fixnum job stages))
  (setf (worker-pool-job pool) job
        (worker-pool-stages pool) stages
        (worker-pool-finished pool) 0
        (worker-pool-failure pool) nil
        (worker-pool-failure-stage pool) most-positive-fixnum
        (worker-pool-modes pool) (sb-vm:floating-point-modes))
  (sb-ext:atomic-incf (worker-pool-generation pool))
  (when (plusp (worker-pool-parked pool))
    (sb-thread:with-mutex ((worker-pool-mutex pool))
      (sb-thread:condition-broadcast (worker-pool-wakeup pool))))
  (run-worker-stages pool 0)
  (let ((others (1- (worker-pool-count pool))) (spins 0))
    (declare (type fixnum spins))
    (loop until (= (worker-pool-finished pool) others)
          do (setf spins (spin-or-yield spins))))
  (let ((failure (worker-pool-failure pool)))
    (when failure
      (setf (worker-pool-failure pool) nil)
      (error failure)))
  pool)

(defun make-worker-pool (count)
  "A pool of COUNT workers: COUNT - 1 threads, parked, and the caller. #W0RKP1"
  (let ((pool (%make-worker-pool count)))
    (setf (worker-pool-events pool) (map-into (make-array count) #'make-event-columns)
          (worker-pool-event-data pool) (map-into (make-array count) (lambda () (make-array 8 :initial-element nil)))
          (worker-pool-pair-sinks pool) (map-into (make-array count) #'make-pair-sink))
    (handler-bind ((serious-condition (lambda (c) (declare (ignore c)) (close-worker-pool pool))))
      (loop for worker from 1 below count
            do (push (sb-thread:make-thread #'worker-loop :name "luv-physics worker"
                                                          :arguments (list pool worker))
                     (worker-pool-threads pool))))
    pool))

(defun close-worker-pool (pool)
  "Let POOL's threads go: wake them to find it closing, and wait for each to end. #W0RKP1"
  (unless (worker-pool-closing pool)
    (setf (worker-pool-closing pool) t)
    (sb-ext:atomic-incf (worker-pool-generation pool))
    (sb-thread:with-mutex ((worker-pool-mutex pool))
      (sb-thread:condition-broadcast (worker-pool-wakeup pool)))
    (mapc #'sb-thread:join-thread (worker-pool-threads pool))
    (setf (worker-pool-threads pool) '()))
  pool)

(defun open-world-workers (world count)
  "Give WORLD a pool of COUNT workers (none for one), closed by a finalizer when WORLD is
dropped; return WORLD. #W0RKP1"
  (when (> count 1)
    (let ((pool (make-worker-pool count)))
      (setf (physics-world-pool world) pool)
      (sb-ext:finalize world (lambda () (close-worker-pool pool)) :dont-save t)))
  world)

(defun close-physics-world (world)
  "Let WORLD's worker threads go; WORLD steps on the calling thread alone from then on. Return
WORLD. #W0RKP1"
  (check-idle world 'close-physics-world)
  (let ((pool (physics-world-pool world)))
    (when pool
      (setf (physics-world-pool world) nil)
      (sb-ext:cancel-finalization world)
      (close-worker-pool pool)))
  world)

(defun physics-world-workers (world)
  "How many workers step WORLD: its pool's count, or 1. #W0RKP1"
  (check-world world 'physics-world-workers)
  (let ((pool (physics-world-pool world)))
    (if pool (worker-pool-count pool) 1)))
;; Workers are threads made once, parked between steps:1 ends here

;; [[file:../physics.org::#SPL1T5][The step's loops cut into fixed pieces:1]]
(defconstant +share-grain+ 8
  "A worker's share of a run of rows starts and ends on a multiple of this many rows. #SPL1T5")

(defconstant +job-velocities+ 0 "The job: integrate velocities by shares of the awake rows. #SPL1T5")
(defconstant +job-pushed-velocities+ 1 "The job: the same, with forces and gravity scales. #SPL1T5")
(defconstant +job-positions+ 2 "The job: integrate positions by shares of the awake rows. #SPL1T5")
(defconstant +job-warm-start+ 3 "The job: the warm start, colour by colour. #SPL1T5")
(defconstant +job-solve+ 4 "The job: a solve or relax pass, colour by colour. #SPL1T5")
(defconstant +job-frames+ 5 "The job: the frame pass, every colour's run shared. #SPL1T5")
(defconstant +job-fill+ 6 "The job: the prepare phase's fill, a piece of every colour's rows each. #SPL1T5")
(defconstant +job-store+ 7 "The job: the store phase, a piece of the rows each. #SPL1T5")

(defgeneric kernel-lanes (kernels)
  (:documentation "The lanes of KERNELS' wide kernels (1 for none), and a function to call after
a wide piece, or NIL. #SPL1T5"))

(defmethod kernel-lanes ((kernels scalar-kernels)) (values 1 nil))

(declaim (inline share-bounds))
(defun share-bounds (start end worker count)
  "The rows of WORKER's share, of COUNT, of the run START..END: two values. #SPL1T5"
  (declare (type index start end) (type fixnum worker count))
  (let* ((blocks (ceiling (- end start) +share-grain+))
         (from (floor (* blocks worker) count))
         (to (floor (* blocks (1+ worker)) count)))
    (values (min end (+ start (* from +share-grain+))) (min end (+ start (* to +share-grain+))))))

(defun run-colour-piece (pool s e wide)
  "Run POOL's colour pass on the rows S..E of one colour: with the wide kernel when WIDE, and the
pool has one, else with the scalar kernel. #SPL1T5"
  (declare (type worker-pool pool) (type index s e))
  (let* ((job (worker-pool-job pool))
         (lanes (if (and wide (worker-pool-wide pool)) (worker-pool-lanes pool) 1))
         (kernel (if (= lanes 1) (worker-pool-narrow pool) (worker-pool-wide pool)))
         (cbuf (worker-pool-cbuf pool)) (v (worker-pool-v pool)))
    (cond ((= job +job-warm-start+) (funcall kernel cbuf v s e))
          ((= job +job-frames+) (funcall kernel cbuf s e))
          (t (solve-handing kernel (if (= lanes 1) 'solve-impact-range (worker-pool-impact pool)) lanes
                            cbuf v (worker-pool-d pool) s e (worker-pool-inv-h pool) (worker-pool-use-bias pool)
                            (worker-pool-elapsed pool) (worker-pool-push-max pool) (worker-pool-threshold pool)
                            (worker-pool-hgx pool) (worker-pool-hgy pool) (worker-pool-hgz pool))))
    (when (and (> lanes 1) (worker-pool-settle pool)) (funcall (worker-pool-settle pool)))))

(defun run-worker-stage (pool worker stage)
  "Run WORKER's piece of stage STAGE of POOL's job. #SPL1T5"
  (declare (type worker-pool pool) (type fixnum worker stage))
  (let ((job (worker-pool-job pool)) (count (worker-pool-count pool)))
    (cond ((>= job +job-fill+)
           ;; a phase's own piece, which cuts its share with share-bounds
           (funcall (the function (worker-pool-piece pool)) worker count))
          ((<= job +job-positions+)
           (multiple-value-bind (s e) (share-bounds 0 (worker-pool-rows pool) worker count)
             (cond ((= job +job-velocities+)
                    (integrate-velocities-range (worker-pool-v pool) s e (worker-pool-h pool)
                                                (worker-pool-gx pool) (worker-pool-gy pool) (worker-pool-gz pool)
                                                (worker-pool-max-speed pool)))
                   ((= job +job-pushed-velocities+)
                    (integrate-pushed-velocities-range (worker-pool-v pool) (worker-pool-pushes pool)
                                                       (worker-pool-handles pool) (worker-pool-masses pool)
                                                       s e (worker-pool-h pool)
                                                       (worker-pool-gx pool) (worker-pool-gy pool) (worker-pool-gz pool)
                                                       (worker-pool-max-speed pool)))
                   (t (integrate-positions-range (worker-pool-v pool) (worker-pool-d pool) s e
                                                 (worker-pool-h pool))))))
          ((= job +job-frames+)
           ;; one stage: a share of every colour's run, the overflow colour's too
           (let ((starts (worker-pool-starts pool)))
             (dotimes (c (1+ +physics-max-colors+))
               (multiple-value-bind (s e) (share-bounds (aref starts c) (aref starts (1+ c)) worker count)
                 (when (< s e) (run-colour-piece pool s e (< c +physics-max-colors+)))))))
          (t
           (let* ((starts (worker-pool-starts pool))
                  (c (aref (worker-pool-stage-colours pool) stage))
                  (start (aref starts c)) (end (aref starts (1+ c))))
             ;; the colour's joints, on worker 0, beside the others' shares of its contacts
             (when (and (= worker 0) (worker-pool-joints pool)) (run-colour-joints pool c))
             (cond ((>= start end))
                   ((or (= c +physics-max-colors+) (< (- end start) (* count (worker-pool-share-rows pool))))
                    (when (= worker 0) (run-colour-piece pool start end (< c +physics-max-colors+))))
                   (t (multiple-value-bind (s e) (share-bounds start end worker count)
                        (when (< s e) (run-colour-piece pool s e t))))))))))

(defun run-colour-joints (pool c)
  "Run POOL's colour pass over the joints of colour C of its joint set: warm start them, or solve
or relax them. #SPL1T5"
  (declare (type worker-pool pool) (type fixnum c))
  (let* ((set (worker-pool-joints pool))
         (js (joint-set-color-starts set))
         (start (aref js c)) (end (aref js (1+ c))))
    (declare (type fixnum-column js) (type index start end))
    (when (< start end)
      (if (= (worker-pool-job pool) +job-warm-start+)
          (warm-start-joints set (worker-pool-v pool) (worker-pool-d pool) start end)
          (solve-joints set (worker-pool-v pool) (worker-pool-d pool) (worker-pool-inv-h pool)
                        (worker-pool-use-bias pool) start end)))))
;; The step's loops cut into fixed pieces:1 ends here

;; [[file:../physics.org::#SPL1T5][The step's loops cut into fixed pieces:2]]
(defconstant +split-probe+ 64
  "Every so many calls of a pass, a tuned pool runs it the way it does not prefer. #SPL1T5")

(defun prefer-split-p (pool job)
  "Whether POOL runs this call of JOB split: when splitting has been the faster per row, but every
+split-probe+th call the other way, so both figures stay current. #SPL1T5"
  (declare (type worker-pool pool) (type fixnum job))
  (let* ((calls (incf (aref (worker-pool-calls pool) job)))
         (prefer (<= (aref (worker-pool-split-ns pool) job) (aref (worker-pool-whole-ns pool) job))))
    (declare (type fixnum calls))
    (if (zerop (mod calls +split-probe+)) (not prefer) prefer)))

(defun note-split-time (pool job split ns rows)
  "Fold NS, the nanoseconds a call of JOB over ROWS rows took, SPLIT or whole, into POOL's running
figure for that way, in nanoseconds per 1024 rows: a call faster than the figure (or the first)
sets it, a slower one moves it an eighth of the way. #SPL1T5"
  (declare (type worker-pool pool) (type fixnum job ns) (type index rows))
  (let ((figures (if split (worker-pool-split-ns pool) (worker-pool-whole-ns pool)))
        (x (floor (* (max ns 0) 1024) (max rows 1))))
    (declare (type fixnum x))
    (setf (aref figures job)
          (let ((old (aref figures job)))
            (if (or (zerop old) (< x old)) x (+ old (floor (- x old) 8)))))))

(defmacro tuned-split ((pool world rows job) split-form whole-form)
  "Run SPLIT-FORM with POOL bound to WORLD's pool when the pass of JOB over ROWS rows splits, else
WHOLE-FORM: a pool with split-rows 0 always splits; one above it splits as prefer-split-p says,
timing each call for note-split-time and counting the calls it split. A pool adds each call's
nanoseconds to its job's spent figure. #SPL1T5"
  (let ((tuning (gensym "TUNING")) (split (gensym "SPLIT")) (start (gensym "START")) (n (gensym "ROWS"))
        (ns (gensym "NS")))
    `(let* ((,n ,rows) (,pool (splitting-pool ,world ,n)))
       (if (null ,pool)
           ,whole-form
           (let* ((,tuning (plusp (worker-pool-split-rows ,pool)))
                  (,split (or (not ,tuning) (prefer-split-p ,pool ,job)))
                  (,start (clock-ns)))
             (multiple-value-prog1 (if ,split ,split-form ,whole-form)
               (let ((,ns (- (clock-ns) ,start)))
                 (incf (aref (worker-pool-spent ,pool) ,job) ,ns)
                 (when ,tuning
                   (when ,split (incf (aref (worker-pool-splits ,pool) ,job)))
                   (note-split-time ,pool ,job ,split ,ns ,n)))))))))

(defun piece-bounds (start end worker count)
  "share-bounds for the phases the page defines before it: the rows of WORKER's share, of COUNT,
of the run START..END. #SPL1T5"
  (declare (type index start end) (type fixnum worker count))
  (share-bounds start end worker count))
;; The step's loops cut into fixed pieces:2 ends here

;; [[file:../physics.org::#SPL1T5][The step's loops cut into fixed pieces:3]]
(defconstant +job-reorder+ 12
  "The job: the prune phase's reordering of the contact rows, a share of the rows each. #SPL1T5")
(defconstant +job-sort-rows+ 13
  "The job: the grid phase's sort of the awake rows, a share of the rows each. #SPL1T5")
(defconstant +job-fold+ 14
  "The job: the finalize phase's fold of the solver's velocities, a share of the awake rows
each. #SPL1T5")
(defconstant +job-colour-rows+ 15
  "The job: the colouring's look-up of each contact's awake rows and the clearing of the masks,
a share of the contacts and of the rows each. #SPL1T5")
(defconstant +job-colour-pairs+ 16
  "The job: the colouring's first pass, over the two-body contacts within its pieces, a share of
the pieces each. #SPL1T5")
(defconstant +job-colour-sides+ 17
  "The job: the colouring's second pass, over the one-sided contacts, a share of the pieces
each. #SPL1T5")
(defconstant +job-colour-order+ 18
  "The job: the prepare phase's ordering of the contacts by colour, a share of the colouring's
pieces each. #SPL1T5")
(defconstant +job-unseen+ 19
  "The job: the prune phase's listing of the contact rows not seen this step, a share of the rows
each. #SPL1T5")

(defun piece-job (kind)
  "The job number of the phase piece KIND names: :fill, :store, :reorder, :sort-rows, :fold,
:colour-rows, :colour-pairs, :colour-sides, :colour-order or :unseen. #SPL1T5"
  (ecase kind
    (:fill +job-fill+) (:store +job-store+) (:reorder +job-reorder+) (:sort-rows +job-sort-rows+)
    (:fold +job-fold+) (:colour-rows +job-colour-rows+) (:colour-pairs +job-colour-pairs+)
    (:colour-sides +job-colour-sides+) (:colour-order +job-colour-order+)
    (:unseen +job-unseen+)))

(defun run-row-pieces (world rows kind move)
  "Run MOVE, a function of the rows FROM below TO, over ROWS rows as a phase piece of KIND
(run-pieces): once for each worker's share of them, or once over them all. #SPL1T5"
  (declare (type index rows) (type function move))
  (flet ((piece (worker count)
           (declare (type fixnum worker count))
           (multiple-value-bind (from to) (piece-bounds 0 rows worker count)
             (declare (type index from to))
             (when (< from to) (funcall move from to)))))
    (declare (dynamic-extent #'piece))
    (run-pieces world rows kind #'piece)))
;; The step's loops cut into fixed pieces:3 ends here

;; [[file:../physics.org::#SPL1T5][The step's loops cut into fixed pieces:4]]
(defun push-piece-event (world worker kind handle-a handle-b x y z speed &optional datum)
  "Record an event found by WORKER's piece of a phase: worker 0's in WORLD's event buffer
(push-event), another worker's, when WORLD records its kind, in that worker's buffer of WORLD's
pool, which run-pieces appends after the pieces before it. #SPL1T5"
  (declare (type fixnum worker kind handle-a handle-b) (type single-float x y z speed))
  (if (zerop worker)
      (push-event world kind handle-a handle-b x y z speed datum)
      (when (logbitp kind (the fixnum (world-event-mask world)))
        (let* ((pool (physics-world-pool world))
               (events (svref (worker-pool-events pool) worker))
               (row (event-columns-append events)))
          (with-event-columns ((k kind) (a handle-a) (b handle-b) (ex x) (ey y) (ez z) (s speed)) events
            (setf (aref k row) kind (aref a row) handle-a (aref b row) handle-b
                  (aref ex row) x (aref ey row) y (aref ez row) z (aref s row) speed))
          (let ((data (svref (worker-pool-event-data pool) worker)))
            (when (>= row (length data))
              (setf data (replace (make-array (* 2 (1+ row)) :initial-element nil) data)
                    (svref (worker-pool-event-data pool) worker) data))
            (setf (svref data row) datum))))))

(defun merge-piece-events (pool world)
  "Append the events the pieces of POOL's workers 1, 2, ... found to WORLD's buffer, in worker
order, after worker 0's, and empty their buffers. #SPL1T5"
  (loop for w from 1 below (worker-pool-count pool)
        do (let ((events (svref (worker-pool-events pool) w))
                 (data (svref (worker-pool-event-data pool) w)))
             (with-event-columns (kind handle-a handle-b x y z speed) events
               (dotimes (row (event-columns-length events))
                 (push-event world (aref kind row) (aref handle-a row) (aref handle-b row)
                             (aref x row) (aref y row) (aref z row) (aref speed row) (svref data row))))
             (fill data nil :end (min (length data) (event-columns-length events)))
             (event-columns-clear events))))

(defun run-pieces (world rows kind piece)
  "Run PIECE, a phase's function of a worker and the count of workers, over ROWS rows: on every
worker of WORLD's pool, each with its number, when the pass of KIND splits (tuned-split), else
once as the one worker of one; then append the pieces' events in worker order. Return how many
pieces ran. The piece, often made on the caller's stack, is the pool's only while its job
runs. #SPL1T5"
  (declare (type function piece))
  (let ((job (piece-job kind)))
    (tuned-split (pool world rows job)
      (progn (dotimes (w (worker-pool-count pool))
               (event-columns-clear (svref (worker-pool-events pool) w)))
             (setf (worker-pool-piece pool) piece)
             (unwind-protect (run-on-workers pool job 1)
               (setf (worker-pool-piece pool) nil))
             (merge-piece-events pool world)
             (worker-pool-count pool))
      (progn (funcall piece 0 1) 1))))
;; The step's loops cut into fixed pieces:4 ends here

;; [[file:../physics.org::#SPL1T5][The step's loops cut into fixed pieces:5]]
(defun splitting-pool (world rows)
  "WORLD's pool when it has one and ROWS, more than none, reach its split-rows, else NIL. #SPL1T5"
  (let ((pool (and (typep world 'physics-world) (physics-world-pool world))))
    (and pool (plusp rows) (>= rows (worker-pool-split-rows pool)) pool)))

(defun awake-rows (world)
  "The awake rows of WORLD, or 0 for something else. #SPL1T5"
  (if (typep world 'physics-world) (body-columns-length (physics-world-awake world)) 0))

(defun constraint-rows (world)
  "The constraint rows of WORLD, or 0 for something else. #SPL1T5"
  (if (typep world 'physics-world) (constraint-columns-length (physics-world-constraints world)) 0))

(defun colour-pass-rows (world)
  "The rows of WORLD a warm start or solve pass splits: its constraint rows, and when its
substeps solve joints, its prepared joints too. #SPL1T5"
  (let ((set (and (typep world 'physics-world) (solving-joints world))))
    (+ (constraint-rows world)
       (if set (aref (joint-set-color-starts set) (1+ +physics-max-colors+)) 0))))

(defun run-colour-pass (pool kernels world job)
  "Write into POOL the kernels of JOB in the family KERNELS for WORLD's features, its buffers and
the stages (the colours with rows, then the overflow colour), and run it on the workers. #SPL1T5"
  (let* ((variant (world-kernel-variant world kernels))
         (starts (physics-world-color-starts world))
         (stage-colours (worker-pool-stage-colours pool))
         (stages 0))
    (declare (type fixnum stages) (type fixnum-column starts))
    (multiple-value-bind (lanes settle) (kernel-lanes kernels)
      (setf (worker-pool-lanes pool) lanes (worker-pool-settle pool) settle))
    (multiple-value-bind (wide narrow)
        (cond ((= job +job-warm-start+)
               (values (kernel-variant-wide-warm-start variant) (kernel-variant-warm-start variant)))
              ((= job +job-solve+) (values (kernel-variant-wide-solve variant) (kernel-variant-solve variant)))
              (t (values (kernel-variant-wide-prepare-frames variant) (kernel-variant-prepare-frames variant))))
      (setf (worker-pool-wide pool) wide (worker-pool-narrow pool) narrow
            (worker-pool-impact pool) (nth-value 3 (wide-kernel-names kernels))))
    (let* ((set (and (/= job +job-frames+) (solving-joints world)))
           (js (and set (joint-set-color-starts set))))
      (declare (type (or null fixnum-column) js))
      (setf (worker-pool-joints pool) set)
      ;; a stage for each colour with contacts or joints, in order, the overflow colour last
      (dotimes (c (1+ +physics-max-colors+))
        (when (or (< (aref starts c) (aref starts (1+ c)))
                  (and js (< (aref js c) (aref js (1+ c)))))
          (setf (aref stage-colours stages) c)
          (incf stages))))
    (setf (worker-pool-cbuf pool) (physics-world-constraints world)
          (worker-pool-v pool) (physics-world-velocities world)
          (worker-pool-d pool) (physics-world-deltas world)
          (worker-pool-starts pool) starts)
    (run-on-workers pool job (if (= job +job-frames+) 1 stages))))

(defun run-rows-pass (pool world job h)
  "Write into POOL WORLD's awake rows, solver arrays and parameters and the substep H, and run
the integration JOB on the workers. #SPL1T5"
  (let ((awake (physics-world-awake world)))
    (setf (worker-pool-v pool) (physics-world-velocities world)
          (worker-pool-d pool) (physics-world-deltas world)
          (worker-pool-rows pool) (body-columns-length awake)
          (worker-pool-h pool) h
          (worker-pool-gx pool) (physics-world-gravity-x world)
          (worker-pool-gy pool) (physics-world-gravity-y world)
          (worker-pool-gz pool) (physics-world-gravity-z world)
          (worker-pool-max-speed pool) (f32 (physics-world-max-speed world)))
    (when (= job +job-pushed-velocities+)
      (setf (worker-pool-pushes pool) (checked-pushes world)
            (worker-pool-handles pool) (body-columns-handle awake)
            (worker-pool-masses pool) (body-columns-inverse-mass awake)))
    (run-on-workers pool job 1)))
;; The step's loops cut into fixed pieces:5 ends here

;; [[file:../physics.org::#SPL1T5][The step's loops cut into fixed pieces:6]]
(defmethod physics-integrate-velocities :around ((kernels scalar-kernels) world h)
  (tuned-split (pool world (awake-rows world) +job-velocities+)
    (progn (check-solver-world 'physics-integrate-velocities world)
           (check-solver-number 'physics-integrate-velocities :h h -1e7)
           (run-rows-pass pool world (if (pushes-live-p world) +job-pushed-velocities+ +job-velocities+) h))
    (call-next-method)))

(defmethod physics-integrate-positions :around ((kernels scalar-kernels) world h)
  (tuned-split (pool world (awake-rows world) +job-positions+)
    (progn (check-solver-world 'physics-integrate-positions world)
           (check-solver-number 'physics-integrate-positions :h h -1e7)
           (run-rows-pass pool world +job-positions+ h))
    (call-next-method)))

(defmethod physics-warm-start :around ((kernels scalar-kernels) world)
  (tuned-split (pool world (colour-pass-rows world) +job-warm-start+)
    (progn (check-solver-world 'physics-warm-start world)
           (run-colour-pass pool kernels world +job-warm-start+))
    (call-next-method)))

(defmethod physics-solve-contacts :around ((kernels scalar-kernels) world inv-h use-bias elapsed)
  (tuned-split (pool world (colour-pass-rows world) +job-solve+)
    (progn (check-solver-world 'physics-solve-contacts world)
           (check-solver-number 'physics-solve-contacts :inv-h inv-h 1.0)
           (check-solver-number 'physics-solve-contacts :elapsed elapsed 0.0)
           (unless (typep use-bias 'boolean)
             (error 'invalid-physics-parameter :world world :name :use-bias :value use-bias :expected "T or NIL"))
           (multiple-value-bind (threshold hgx hgy hgz) (impact-parameters world)
             (setf (worker-pool-inv-h pool) inv-h (worker-pool-use-bias pool) use-bias
                   (worker-pool-elapsed pool) elapsed (worker-pool-push-max pool) (f32 (physics-world-push-max world))
                   (worker-pool-threshold pool) threshold
                   (worker-pool-hgx pool) hgx (worker-pool-hgy pool) hgy (worker-pool-hgz pool) hgz))
           (run-colour-pass pool kernels world +job-solve+))
    (call-next-method)))

(defmethod physics-prepare-frames :around ((kernels scalar-kernels) world)
  (tuned-split (pool world (constraint-rows world) +job-frames+)
    (run-colour-pass pool kernels world +job-frames+)
    (call-next-method)))
;; The step's loops cut into fixed pieces:6 ends here

;; [[file:../physics.org::#P41P1C][The pair phase in pieces:1]]
(defconstant +job-pairs+ 8 "The job: the pair phase's listed pairs, a share of the list each. #P41P1C")

(defconstant +body-row-weight+ 8
  "How many rows a body counts as against a pool's split-rows in the passes that take a body a
row: the list's build and the terrain phase. #P41P1C")
(defconstant +job-pair-refresh+ 11
  "The job: the merge of the pair phase's pieces, each worker refreshing its own sink's rows. #P41P1C")
(defconstant +job-pair-build+ 9
  "The job: the pair list's build, a share of the awake grid's places each. #P41P1C")

(defun pair-sink-ready (sink rows near cursor)
  "Empty SINK for a piece over ROWS awake rows, with a neighbour scratch of NEAR places and
CURSOR, the contact table's, as its first guess. #P41P1C"
  (declare (type pair-sink sink) (type index rows near cursor))
  (let ((list (pair-sink-list sink)))
    (setf (pair-list-overlaps list) (fixnum-room (pair-list-overlaps list) rows :keep 0)
          (pair-list-count list) 0 (pair-list-examined list) 0)
    (fill (pair-list-overlaps list) 0 :end rows))
  (setf (pair-sink-near sink) (fixnum-room (pair-sink-near sink) near :keep 0))
  (pair-sink-start sink cursor))

(defun struck-pair-piece (world sink packed)
  "Take the listed pair PACKED, which strikes, whole, with its impact normal, into SINK, its
overlap already counted: as the pair phase takes it after scan-listed-pairs. #P41P1C"
  (declare (type pair-sink sink) (type fixnum packed))
  (with-world-parameters (margin slop (threshold restitution-threshold)) world
    (let* ((i (ash packed -24)) (j (logand packed #xFFFFFF))
           (dt (physics-world-current-dt world)))
      (declare (type index i j) (type single-float margin slop threshold dt))
      (with-body-columns (x y z vx vy vz radius handle) (physics-world-awake world)
        (pair-contact (physics-world-contacts world) (physics-world-contact-table world)
                      (pair-list-overlaps (pair-sink-list sink)) margin slop dt (gravity-step world dt)
                      threshold t
                      (aref x i) (aref y i) (aref z i) (aref radius i) (aref handle i)
                      (aref vx i) (aref vy i) (aref vz i)
                      (aref x j) (aref y j) (aref z j) (aref radius j) (aref handle j)
                      (aref vx j) (aref vy j) (aref vz j) -1 -1 sink))))
  sink)

(defun listed-pairs-piece (world sink from to)
  "The listed pairs of WORLD's pair list at places FROM below TO, as the pair phase takes them
(walk-listed-pairs, then each that strikes whole), into SINK. #P41P1C"
  (declare (type pair-sink sink) (type index from to))
  (let ((pairs (pair-list-pairs (physics-world-pair-list world)))
        (overlaps (pair-list-overlaps (pair-sink-list sink)))
        (p from))
    (declare (type fixnum-column pairs overlaps) (type index p))
    (loop (setf p (walk-listed-pairs world p to nil sink overlaps))
          (when (>= p to) (return))
          (struck-pair-piece world sink (aref pairs p))
          (incf p))
    sink))

(defun build-pairs-piece (world sink from to)
  "The walks of the bodies at places FROM below TO of WORLD's awake grid, as the pair list's
build walks them (pair-list-walks), with SINK's neighbour scratch: its pairs, candidates and
overlaps into SINK's list, its touches into SINK. #P41P1C"
  (declare (type pair-sink sink) (type index from to))
  (with-world-parameters (margin (skin pair-skin) slop (rmax max-radius) (threshold restitution-threshold)) world
    (let* ((awake (physics-world-awake world))
           (grid (physics-world-awake-grid world))
           (plist (pair-sink-list sink))
           (dt (physics-world-current-dt world))
           (gstep (gravity-step world dt))
           (contacts (physics-world-contacts world))
           (table (physics-world-contact-table world))
           (crowded nil)
           (filtering (physics-world-filtering world)))
      (declare (type single-float margin skin slop dt gstep rmax threshold) (type body-columns awake)
               (type pair-list plist) (type contact-columns contacts) (type contact-table table)
               (type hash-grid grid) #.+kernel-policy+)
      (with-body-columns (x y z vx vy vz radius flags handle) awake
        (macrolet ((pair-of-rows (i j)
                     `(when (pair-contact contacts table (pair-list-overlaps plist) margin slop dt gstep threshold t
                                          (aref x ,i) (aref y ,i) (aref z ,i) (aref radius ,i) (aref handle ,i)
                                          (aref vx ,i) (aref vy ,i) (aref vz ,i)
                                          (aref x ,j) (aref y ,j) (aref z ,j) (aref radius ,j) (aref handle ,j)
                                          (aref vx ,j) (aref vy ,j) (aref vz ,j) ,i ,j sink)
                        (setf crowded t))))
          (pair-list-walks from to (pair-sink-near sink))))))
  sink)

(defun fold-piece-overlaps (pool plist rows)
  "Make PLIST's overlap count of each of ROWS awake rows the sum of the counts of POOL's workers'
sinks; return the largest. #P41P1C"
  (declare (type worker-pool pool) (type pair-list plist) (type index rows))
  (let ((overlaps (pair-list-overlaps plist)) (sinks (worker-pool-pair-sinks pool)) (most 0))
    (declare (type fixnum-column overlaps) (type fixnum most))
    (replace overlaps (pair-list-overlaps (pair-sink-list (svref sinks 0))) :end1 rows)
    (loop for w from 1 below (worker-pool-count pool)
          do (let ((more (pair-list-overlaps (pair-sink-list (svref sinks w)))))
               (declare (type fixnum-column more))
               (dotimes (i rows) (setf (aref overlaps i) (+ (aref overlaps i) (aref more i))))))
    (dotimes (i rows most) (setf most (max most (aref overlaps i))))))

(defun merge-pair-sink (world sink)
  "Hand SINK's touches to WORLD's contacts in order, as one walk would have: the table's cursor
set on each touch's row, and a miss counted where the cursor would not have guessed it. #P41P1C"
  (declare (type pair-sink sink) (inline touch-contact))
  (let ((contacts (physics-world-contacts world)) (table (physics-world-contact-table world))
        (f (pair-sink-touches sink)) (g (pair-sink-geometry sink)))
    (declare (type contact-columns contacts) (type contact-table table) (type fixnum-column f)
             (type f32-column g))
    (dotimes (k (pair-sink-count sink) sink)
      (let ((row (aref f (* 5 k))) (key (aref f (+ (* 5 k) 1))) (q (* 7 k)))
        (declare (type fixnum row key) (type index q))
        (when (>= row 0)
          (let ((guess (contact-table-cursor table)))
            (unless (and (< guess (contact-columns-length contacts))
                         (= (aref (contact-columns-key contacts) guess) key))
              (incf (contact-table-misses table))
              (setf (contact-table-cursor table) row))))
        (touch-contact contacts table key (aref f (+ (* 5 k) 2)) (aref f (+ (* 5 k) 3)) (aref f (+ (* 5 k) 4))
                       (aref g q) (aref g (+ q 1)) (aref g (+ q 2)) (aref g (+ q 3))
                       (aref g (+ q 4)) (aref g (+ q 5)) (aref g (+ q 6)) 0.0 0.0 0.0)))))

(defun place-piece-touches (pool world)
  "Ready the touches of POOL's workers' sinks to be refreshed in pieces (refresh-sink-rows), as
merge-pair-sink would take them in worker order: append a row for each new contact, in order,
into WORLD's contacts and table, and note it in its touch; give each sink the place in the
step's order of its first fresh touch; leave the table's cursor, misses and touched count as
the merge leaves them. #P41P1C"
  (declare (type worker-pool pool))
  (let* ((contacts (physics-world-contacts world)) (table (physics-world-contact-table world))
         (step (contact-table-step table))
         (start (contact-table-cursor table)) (cursor start)
         (misses (contact-table-misses table)) (touched (contact-table-touched table)))
    (declare (type contact-columns contacts) (type contact-table table) (type fixnum step misses)
             (type index start cursor touched))
    (dotimes (w (worker-pool-count pool))
      (let* ((sink (svref (worker-pool-pair-sinks pool) w))
             (first (pair-sink-first-row sink)) (f (pair-sink-touches sink)) (new (pair-sink-new sink)))
        (declare (type fixnum first) (type fixnum-column f new))
        ;; the piece guessed its first row found again from START; the walk, from CURSOR
        (incf misses (pair-sink-misses sink))
        (when (>= first 0)
          (unless (= start first) (decf misses))
          (unless (= cursor first) (incf misses))
          (setf cursor (pair-sink-cursor sink)))
        (setf (pair-sink-order sink) touched)
        (incf touched (pair-sink-fresh sink))
        (dotimes (n (pair-sink-new-count sink))
          (let* ((o (* 5 (aref new n))) (key (aref f (+ o 1))) (row (contact-columns-append contacts)))
            (declare (type index o) (type fixnum key row))
            (contact-table-put table key row)
            (with-contact-columns ((a handle-a) (b handle-b) (k kind) (ky key) seen) contacts
              (setf (aref a row) (aref f (+ o 3)) (aref b row) (aref f (+ o 4)) (aref k row) (aref f (+ o 2))
                    (aref ky row) key)
              (unless (= (aref seen row) step) (incf touched)))
            (setf (aref f o) row)))))
    (setf (contact-table-cursor table) cursor (contact-table-misses table) misses
          (contact-table-touched table) touched)
    pool))

(defun refresh-sink-rows (world sink)
  "Refresh the contact rows of SINK's touches, each found or placed (place-piece-touches), with
their geometry, stamping each not yet seen this step with the next place of the step's order
from SINK's: what merge-pair-sink does to them once their rows are known. #P41P1C"
  (declare (type pair-sink sink) (inline refresh-contact))
  (let* ((contacts (physics-world-contacts world))
         (step (contact-table-step (physics-world-contact-table world)))
         (f (pair-sink-touches sink)) (g (pair-sink-geometry sink)) (place (pair-sink-order sink)))
    (declare (type contact-columns contacts) (type fixnum step) (type fixnum-column f) (type f32-column g)
             (type index place))
    (dotimes (k (pair-sink-count sink) sink)
      (let ((q (* 7 k)))
        (declare (type index q))
        (when (refresh-contact contacts (aref f (* 5 k)) step place
                               (aref g q) (aref g (+ q 1)) (aref g (+ q 2)) (aref g (+ q 3))
                               (aref g (+ q 4)) (aref g (+ q 5)) (aref g (+ q 6)) 0.0 0.0 0.0)
          (incf place))))))

(defun gather-piece-pairs (pool plist)
  "Append the pairs POOL's workers' sinks listed to PLIST, in worker order, and sum the candidates
they examined. #P41P1C"
  (declare (type worker-pool pool) (type pair-list plist))
  (loop for w below (worker-pool-count pool)
        do (let* ((list (pair-sink-list (svref (worker-pool-pair-sinks pool) w)))
                  (k (pair-list-count plist)) (more (pair-list-count list)))
             (setf (pair-list-pairs plist) (fixnum-room (pair-list-pairs plist) (+ k more) :least 1024))
             (replace (pair-list-pairs plist) (pair-list-pairs list) :start1 k :end2 more)
             (setf (pair-list-count plist) (+ k more))
             (incf (pair-list-examined plist) (pair-list-examined list))))
  plist)

(defun run-pair-pieces (pool world kind)
  "Run the pair phase's walk KIND (:listed or :build) in pieces on POOL's workers, then merge
their sinks into WORLD in worker order; return true, or NIL, having changed nothing, when some
row's overlaps reach +overlaps-per-body+: then one walk would have become crowded. #P41P1C"
  (declare (type worker-pool pool))
  (let* ((build (eq kind :build))
         (plist (physics-world-pair-list world))
         (grid (physics-world-awake-grid world))
         (places (if build (hash-grid-count grid) (pair-list-count plist)))
         (rows (awake-rows world))
         (near (length (hash-grid-near grid)))
         (cursor (contact-table-cursor (physics-world-contact-table world)))
         (sinks (worker-pool-pair-sinks pool)))
    (declare (type index places rows near cursor))
    (flet ((piece (worker count)
             (declare (type fixnum worker count))
             (let ((sink (svref sinks worker)))
               (pair-sink-ready sink rows near cursor)
               (multiple-value-bind (s e) (share-bounds 0 places worker count)
                 (if build (build-pairs-piece world sink s e) (listed-pairs-piece world sink s e))))))
      (declare (dynamic-extent #'piece))
      (setf (worker-pool-piece pool) #'piece)
      (unwind-protect (run-on-workers pool (if build +job-pair-build+ +job-pairs+) 1)
        (setf (worker-pool-piece pool) nil)))
    (let* ((start (clock-ns)) (job (if build +job-pair-build+ +job-pairs+))
           (merged (< (fold-piece-overlaps pool plist rows) +overlaps-per-body+)))
      (if merged
          (progn (when build (gather-piece-pairs pool plist))
                 (place-piece-touches pool world))
          (fill (pair-list-overlaps plist) 0 :end rows))
      (incf (aref (worker-pool-merged pool) job) (- (clock-ns) start))
      (when merged
        (flet ((refresh (worker count)
                 (declare (type fixnum worker) (ignore count))
                 (refresh-sink-rows world (svref sinks worker))))
          (declare (dynamic-extent #'refresh))
          (setf (worker-pool-piece pool) #'refresh start (clock-ns))
          (unwind-protect (run-on-workers pool +job-pair-refresh+ 1)
            (setf (worker-pool-piece pool) nil))
          ;; a part of its pair job's spent figure already: kept apart for the claims only
          (incf (aref (worker-pool-spent pool) +job-pair-refresh+) (- (clock-ns) start))))
      merged)))

(defun pairs-in-pieces (world kind whole)
  "Take the pair phase's walk KIND (:listed or :build) in pieces on WORLD's workers when its pool
splits the pass (tuned-split) and no row becomes crowded, else by calling WHOLE, the phase's own
walk. #P41P1C"
  (declare (type function whole))
  (let ((job (if (eq kind :build) +job-pair-build+ +job-pairs+))
        (places (if (eq kind :build)
                    (* +body-row-weight+ (hash-grid-count (physics-world-awake-grid world)))
                    (pair-list-count (physics-world-pair-list world)))))
    (tuned-split (pool world places job)
      (unless (run-pair-pieces pool world kind) (funcall whole))
      (funcall whole))))
;; The pair phase in pieces:1 ends here

;; [[file:../physics.org::#MYWP1C][The terrain phase in pieces:1]]
(defconstant +job-terrain+ 10 "The job: the terrain phase, a share of the awake rows each. #MYWP1C")

(defun terrain-rows-piece (world sink from to)
  "The terrain phase's awake rows FROM below TO of WORLD (terrain-rows), read through SINK's own
probe, their touches and their count of buried bodies into SINK. #MYWP1C"
  (declare (type pair-sink sink) (type index from to))
  (let ((probe (pair-sink-probe sink)))
    (reset-terrain-probe probe (physics-world-terrain world))
    (setf (pair-sink-buried sink) (terrain-rows world from to sink probe)))
  sink)

(defun run-terrain-pieces (pool world)
  "Run WORLD's terrain rows in pieces on POOL's workers, then hand their touches to WORLD's
contacts in worker order; return how many bodies lie buried. #MYWP1C"
  (declare (type worker-pool pool))
  (let ((rows (awake-rows world))
        (cursor (contact-table-cursor (physics-world-contact-table world)))
        (sinks (worker-pool-pair-sinks pool)))
    (declare (type index rows cursor))
    (flet ((piece (worker count)
             (declare (type fixnum worker count))
             (let ((sink (svref sinks worker)))
               (pair-sink-start sink cursor)
               (multiple-value-bind (s e) (share-bounds 0 rows worker count)
                 (terrain-rows-piece world sink s e)))))
      (declare (dynamic-extent #'piece))
      (setf (worker-pool-piece pool) #'piece)
      (unwind-protect (run-on-workers pool +job-terrain+ 1)
        (setf (worker-pool-piece pool) nil)))
    (let ((start (clock-ns)) (buried 0))
      (declare (type fixnum buried))
      (dotimes (w (worker-pool-count pool))
        (merge-pair-sink world (svref sinks w))
        (incf buried (pair-sink-buried (svref sinks w))))
      (incf (aref (worker-pool-merged pool) +job-terrain+) (- (clock-ns) start))
      buried)))

(defun terrain-in-pieces (world whole)
  "Take WORLD's terrain rows in pieces on its workers when its pool splits the pass (tuned-split),
else by calling WHOLE, the phase's own walk; return how many bodies lie buried. #MYWP1C"
  (declare (type function whole))
  (tuned-split (pool world (* +body-row-weight+ (awake-rows world)) +job-terrain+)
    (run-terrain-pieces pool world)
    (funcall whole)))
;; The terrain phase in pieces:1 ends here

;; [[file:../physics.org::#SNFRMT][The format: a header, then parts padded to words:1]]
(deftype octets () "A snapshot's bytes. #SNFRMT" '(simple-array (unsigned-byte 8) (*)))

(defconstant +snapshot-version+ 5 "The version of the snapshot layout this engine writes and reads. #SNFRMT")

(defconstant +snapshot-header-bytes+ 32 "Bytes of a snapshot's header: magic, version, parts, size, checksum. #SNFRMT")

(defconstant +snapshot-body-bytes+ 70
  "Bytes of one body's record in a snapshot but its material's index, which takes 1, 2 or 4 bytes
as the palette has up to 256, up to 65536 or more entries (material-index-bytes). #SNFRMT")

(declaim (inline material-index-bytes body-record-bytes))
(defun material-index-bytes (materials)
  "The bytes a body's index into a palette of MATERIALS entries takes in a snapshot. #SNFRMT"
  (declare (type index materials))
  (cond ((<= materials 256) 1) ((<= materials 65536) 2) (t 4)))

(defun body-record-bytes (materials)
  "The bytes one body takes in a snapshot whose palette has MATERIALS entries. #SNFRMT"
  (declare (type index materials))
  (+ +snapshot-body-bytes+ (material-index-bytes materials)))

(defconstant +snapshot-material-bytes+ 36 "Bytes of one entry of a snapshot's palette of materials. #SNFRMT")

(defconstant +snapshot-contact-bytes+ 10
  "Bytes every contact has in a snapshot: its key and its flags; its normal and its groups of
carried impulses go into the part's streams when the flags say so. #SNFRMT")

(defconstant +snapshot-contact-head-bytes+ 24
  "Bytes of the contact part's payload before its keys: the count of contacts and the counts of
its five streams. #SNFRMT")

(defconstant +snapshot-contact-most-bytes+ 50
  "The most bytes a contact takes in a snapshot: its key, its flags, its normal and every group of
carried impulses. #SNFRMT")

(defconstant +snapshot-pair-row-bytes+ 12 "Bytes of one row's anchor in the pair list of a snapshot. #SNFRMT")

(defconstant +snapshot-pair-head-bytes+ 40 "Bytes of the pair list part's payload before its rows. #SNFRMT")

(defconstant +snapshot-box-bytes+ 52 "Bytes of one posted box in a snapshot. #SNFRMT")

(defconstant +snapshot-box-body-bytes+ 24
  "Bytes of one box body's record in the box part of a snapshot: its slot, its three half-extents,
and the first and the count of its points. #SNFRMT")

(defconstant +snapshot-box-point-bytes+ 20
  "Bytes of one box point of the last step in a snapshot: its key and its three carried impulses. #SNFRMT")

(declaim (inline box-part-bytes))
(defun box-part-bytes (boxes points)
  "The payload bytes of a box part of BOXES box bodies and POINTS points. #SNFRMT"
  (declare (type index boxes points))
  (+ 8 (* +snapshot-box-body-bytes+ boxes) (* +snapshot-box-point-bytes+ points)))
;; The format: a header, then parts padded to words:1 ends here

;; [[file:../physics.org::#SNFRMT][The format: a header, then parts padded to words:2]]
(defparameter +snapshot-magic+ (map 'octets #'char-code "LUVWORLD")
  "The eight bytes a snapshot starts with. #SNFRMT")

#-little-endian
(error "The snapshot's accessors read and write the machine's own byte order, which must be little-endian. #SNFRMT")

(declaim (inline snap-u8 snap-u16 snap-u32 snap-i32 snap-u64 snap-i64 snap-f32 snap-f64
                 (setf snap-u8) (setf snap-u16) (setf snap-u32) (setf snap-i32) (setf snap-u64)
                 (setf snap-i64) (setf snap-f32) (setf snap-f64)))
(macrolet ((def (name ref type)
             `(progn
                (defun ,name (buffer offset)
                  ,(format nil "The ~(~A~) at byte OFFSET of BUFFER, little-endian. #SNFRMT" type)
                  (declare (type octets buffer) (type index offset) #.+kernel-policy+)
                  (sb-sys:with-pinned-objects (buffer) (,ref (sb-sys:vector-sap buffer) offset)))
                (defun (setf ,name) (value buffer offset)
                  ,(format nil "Write the ~(~A~) VALUE at byte OFFSET of BUFFER, little-endian. #SNFRMT" type)
                  (declare (type octets buffer) (type index offset) (type ,type value) #.+kernel-policy+)
                  (sb-sys:with-pinned-objects (buffer) (setf (,ref (sb-sys:vector-sap buffer) offset) value))))))
  (def snap-u8 sb-sys:sap-ref-8 (unsigned-byte 8))
  (def snap-u16 sb-sys:sap-ref-16 (unsigned-byte 16))
  (def snap-u32 sb-sys:sap-ref-32 (unsigned-byte 32))
  (def snap-i32 sb-sys:signed-sap-ref-32 (signed-byte 32))
  (def snap-u64 sb-sys:sap-ref-64 (unsigned-byte 64))
  (def snap-i64 sb-sys:signed-sap-ref-64 (signed-byte 64))
  (def snap-f32 sb-sys:sap-ref-single single-float)
  (def snap-f64 sb-sys:sap-ref-double double-float))
;; The format: a header, then parts padded to words:2 ends here

;; [[file:../physics.org::#SNFRMT][The format: a header, then parts padded to words:3]]
;;; the parts of a snapshot, in order: each part's id, its name and the bytes of its payload

(defparameter +snapshot-parts+
  '((1 :world) (2 :handles) (3 :awake-bodies) (4 :sleeping-bodies) (5 :materials) (6 :contacts)
    (7 :pair-list) (8 :boxes) (9 :pushes) (10 :joints :optional) (11 :box-bodies :optional))
  "The parts of a snapshot, in the order they are written, each its id and its name, and
:optional for a part a world may not have (then it is not written and its size is -1): each part
of the world's state is one entry. #SNFRMT")

(defconstant +snapshot-joint-bytes+ 88 "Bytes of one joint's record in a snapshot. #SNFRMT")

(defconstant +snapshot-world-bytes+ 204 "Bytes of the world part's payload. #SNFRMT")

(declaim (inline padded))
(defun padded (bytes)
  "BYTES rounded up to a multiple of 4. #SNFRMT"
  (declare (type index bytes))
  (logandc2 (+ bytes 3) 3))

(defun features-mask (features)
  "The bit mask of FEATURES, bit K for the K-th feature of +physics-features+. #SNFRMT"
  (loop for f in features sum (ash 1 (position f +physics-features+))))
;; The format: a header, then parts padded to words:3 ends here

;; [[file:../physics.org::#SNSUMS][A checksum of four lanes of two sums:1]]
(declaim (inline snapshot-checksum))
(defun snapshot-checksum (buffer start end)
  "The 64-bit checksum of the bytes START..END of BUFFER (END - START a multiple of 4): four lanes
of Fletcher's two sums over 64-bit words, lane K taking the words K, K + 4, K + 8 ... (A, the sum
of its words, and B, the sum of its A's, both modulo 2^64) and lane 0 the last whole words; then
the eight sums and a last 32-bit word folded by FNV-1a's step, in that order, each step followed
by its high half shifted into its low. A change within one word always changes its lane's A, and
the fold keeps it. #SNSUMS"
  (declare (type octets buffer) (type index start end) #.+kernel-policy+)
  (let ((a0 0) (a1 0) (a2 0) (a3 0) (b0 0) (b1 0) (b2 0) (b3 0) (i start))
    (declare (type (unsigned-byte 64) a0 a1 a2 a3 b0 b1 b2 b3) (type index i))
    (macrolet ((sum (a b word) `(setf ,a (logand (+ ,a ,word) #xFFFFFFFFFFFFFFFF)
                                      ,b (logand (+ ,b ,a) #xFFFFFFFFFFFFFFFF)))
               ;; the shift carries a change in the top bits down, where the next multiply spreads
               ;; it: without it a change of 2^63 in A and in B cancels
               (fnv (hash word) `(setf ,hash (logand (* (logxor ,hash ,word) 1099511628211) #xFFFFFFFFFFFFFFFF)
                                       ,hash (logxor ,hash (ash ,hash -32)))))
      (sb-sys:with-pinned-objects (buffer)
        (let ((sap (sb-sys:sap+ (sb-sys:vector-sap buffer) start)))
          ;; four chains of adds in flight at once, the pointer moved, not an index scaled
          (loop while (<= (+ i 32) end)
                do (sum a0 b0 (sb-sys:sap-ref-64 sap 0)) (sum a1 b1 (sb-sys:sap-ref-64 sap 8))
                   (sum a2 b2 (sb-sys:sap-ref-64 sap 16)) (sum a3 b3 (sb-sys:sap-ref-64 sap 24))
                   (setf sap (sb-sys:sap+ sap 32))
                   (incf i 32))
          (loop while (<= (+ i 8) end)
                do (sum a0 b0 (sb-sys:sap-ref-64 sap 0)) (setf sap (sb-sys:sap+ sap 8)) (incf i 8))
          (let ((hash 14695981039346656037))
            (declare (type (unsigned-byte 64) hash))
            (fnv hash a0) (fnv hash a1) (fnv hash a2) (fnv hash a3)
            (fnv hash b0) (fnv hash b1) (fnv hash b2) (fnv hash b3)
            (when (< i end) (fnv hash (sb-sys:sap-ref-32 sap 0)))
            hash))))))
;; A checksum of four lanes of two sums:1 ends here

;; [[file:../physics.org::#SNSCRT][A scratch for each world:1]]
;;; the scratch a snapshot and a restore reuse: one set per world, grown by doubling

(defstruct (snapshot-scratch (:constructor make-snapshot-scratch ()))
  "What taking and restoring a world's snapshots reuse: the palette index of each body
(MATERIALS), the palette's words (PALETTE, nine a material) and its open-addressing table
(TABLE), marks by handle slot (MARKS, stamped with STAMP), a contact table and contact rows
filled while a snapshot is checked and traded for the world's when it is restored (CONTACTS,
CONTACT-ROWS), the pair list's pairs decoded while a snapshot is checked and traded for the
world's when it is restored (PAIRS), the chunks found last (CHUNK-KEYS, CHUNKS), the contact
streams' words (STREAMS), and each part's size and offset. #SNSCRT"
  (materials (make-array 64 :element-type 'fixnum) :type fixnum-column)
  (palette (make-array 576 :element-type 'fixnum) :type fixnum-column)
  (count 0 :type index)
  (table (make-array 128 :element-type 'fixnum :initial-element -1) :type fixnum-column)
  (marks (make-array 64 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (stamp 0 :type fixnum)
  (contacts (make-contact-table) :type contact-table)
  (contact-rows nil :type (or null contact-columns))
  (pairs (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (chunk-keys (make-array 16 :element-type 'fixnum :initial-element -1) :type fixnum-column)
  (chunks (make-array 16 :initial-element nil) :type simple-vector)
  (streams (make-array 0 :element-type '(unsigned-byte 32)) :type (simple-array (unsigned-byte 32) (*)))
  (sizes (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column)
  (offsets (make-array 16 :element-type 'fixnum :initial-element 0) :type fixnum-column))

(defun world-snapshot-scratch (world)
  "WORLD's snapshot scratch, made at its first snapshot or restore: each world has its own, so
worlds stepped on different threads take and restore snapshots at the same time. #SNSCRT"
  (or (physics-world-snapshot-scratch world)
      (setf (physics-world-snapshot-scratch world) (make-snapshot-scratch))))

(defun snapshot-marks (scratch slots)
  "SCRATCH's marks, with room for SLOTS slots, under two fresh stamps: return the marks and the
first, S, which marks free slots, while S + 1 marks live ones and is SCRATCH's stamp from now on;
any mark below S is no mark. #SNSCRT"
  (declare (type snapshot-scratch scratch) (type index slots))
  (when (< (length (snapshot-scratch-marks scratch)) slots)
    (setf (snapshot-scratch-marks scratch)
          (make-array (max slots (* 2 (length (snapshot-scratch-marks scratch)))) :element-type 'fixnum
                                                                                 :initial-element 0)))
  (incf (snapshot-scratch-stamp scratch) 2)
  (values (snapshot-scratch-marks scratch) (1- (snapshot-scratch-stamp scratch))))
;; A scratch for each world:1 ends here

;; [[file:../physics.org::#SNTAKE][Taking a snapshot: a bound, then each part in its order:1]]
(defun snapshot-part-bounds (world materials sizes)
  "Write into SIZES, by part id, the most payload bytes each part of WORLD's snapshot may take,
given its palette of MATERIALS entries (-1 for a part the world has not got), and return their
sum with the parts' own headers: the exact size of every part but the contacts, whose records
are bounded by +snapshot-contact-most-bytes+, and the pair list, bounded by its rows' handles
and its pairs written out whole. #SNTAKE"
  (declare (type fixnum-column sizes) (type index materials) #.+kernel-policy+)
  (let* ((ids (physics-world-ids world))
         (free (loop with slot = (handle-table-free ids) while (>= slot 0)
                     count t do (setf slot (aref (handle-table-local ids) slot))))
         (plist (physics-world-pair-list world))
         (rows (max 0 (pair-list-rows plist))))
    (setf (aref sizes 1) +snapshot-world-bytes+
          (aref sizes 2) (+ 12 (* 4 (handle-table-count ids)) (* 4 free) (* 8 (physics-world-added-count world)))
          (aref sizes 3) (padded (+ 4 (* (body-record-bytes materials) (body-columns-length (physics-world-awake world)))))
          (aref sizes 4) (padded (+ 4 (* (body-record-bytes materials) (body-columns-length (physics-world-sleeping world)))))
          (aref sizes 5) (+ 4 (* +snapshot-material-bytes+ materials))
          (aref sizes 6) (padded (+ +snapshot-contact-head-bytes+ 40 (* +snapshot-contact-most-bytes+ (contact-columns-length (physics-world-contacts world)))))
          (aref sizes 7) (+ +snapshot-pair-head-bytes+ (* (+ +snapshot-pair-row-bytes+ 8) rows) (* 4 (ceiling rows 32))
                            (* 8 (if (>= (pair-list-rows plist) 0) (pair-list-count plist) 0)) 8)
          (aref sizes 8) (+ 4 (* +snapshot-box-bytes+ (box-columns-length (physics-world-boxes world))))
          (aref sizes 9) (+ 4 (if (physics-world-pushes world) (* 16 (handle-table-count ids)) 0))
          (aref sizes 10) (let ((set (physics-world-joints world)))
                            (if set
                                (let ((jids (joint-set-ids set)))
                                  (+ 20 (* 4 (handle-table-count jids))
                                     (* 4 (loop with slot = (handle-table-free jids) while (>= slot 0)
                                                count t do (setf slot (aref (handle-table-local jids) slot))))
                                     (* +snapshot-joint-bytes+ (joint-columns-length (joint-set-rows set)))))
                                -1))
          (aref sizes 11) (let ((set (physics-world-box-bodies world)))
                            (if set (box-part-bytes (box-set-live set) (box-point-columns-length (box-set-points set))) -1)))
    (loop for (id) in +snapshot-parts+ unless (minusp (aref sizes id)) sum (+ 8 (aref sizes id)))))

(defun snapshot-physics-world (world &optional buffer)
  "Write WORLD's whole simulation state into BUFFER, an octet vector, when it has room for the
snapshot's bound (snapshot-part-bounds), else into a new one of that bound; return the buffer
and the snapshot's size in bytes. Into a buffer large enough it conses nothing. #SNTAKE"
  (check-idle world 'snapshot-physics-world)
  (unless (or (null buffer) (typep buffer 'octets))
    (error 'invalid-physics-parameter :world world :name :buffer :value buffer
                                      :expected "NIL or an octet vector, (simple-array (unsigned-byte 8) (*))"))
  (let* ((scratch (world-snapshot-scratch world))
         (materials (snapshot-materials world scratch))
         (sizes (snapshot-scratch-sizes scratch))
         (bound (+ +snapshot-header-bytes+ (snapshot-part-bounds world materials sizes))))
    (declare (type index bound))
    (let ((buffer (if (and buffer (>= (length buffer) bound)) buffer (make-array bound :element-type '(unsigned-byte 8))))
          (at +snapshot-header-bytes+))
      (declare (type octets buffer) (type index at))
      (replace buffer +snapshot-magic+)
      (setf (snap-u32 buffer 8) +snapshot-version+
            (snap-u32 buffer 12) (loop for (id) in +snapshot-parts+ count (>= (aref sizes id) 0)))
      ;; each part writes its payload, padding zeroed, and says how long it came out
      (loop for (id) in +snapshot-parts+
            unless (minusp (aref sizes id))
              do (let ((size (write-snapshot-part id world buffer (+ at 8) scratch)))
                   (declare (type index size))
                   (setf (snap-u32 buffer at) id (snap-u32 buffer (+ at 4)) size)
                   (incf at (+ 8 size))))
      (setf (snap-u64 buffer 16) at
            (snap-u64 buffer 24) (snapshot-checksum buffer +snapshot-header-bytes+ at))
      (values buffer at))))
;; Taking a snapshot: a bound, then each part in its order:1 ends here

;; [[file:../physics.org::#SNTAKE][Taking a snapshot: a bound, then each part in its order:2]]
(defun write-snapshot-part (id world buffer at scratch)
  "Write the payload of part ID of WORLD's snapshot into BUFFER from AT, its padding zeroed, and
return its bytes. #SNTAKE"
  (declare (type octets buffer) (type index at) (type snapshot-scratch scratch) #.+kernel-policy+)
  (ecase id
    (1 (fill buffer 0 :start at :end (+ at +snapshot-world-bytes+))
       (write-snapshot-world world buffer at)
       +snapshot-world-bytes+)
    (2 (let* ((ids (physics-world-ids world)) (count (handle-table-count ids))
              (generations (handle-table-generation ids)) (locals (handle-table-local ids))
              (free-at (+ at 8 (* 4 count))) (nfree 0))
         (declare (type index count nfree))
         (setf (snap-u32 buffer at) count)
         (dotimes (slot count) (setf (snap-u32 buffer (+ at 8 (* 4 slot))) (aref generations slot)))
         (loop with slot of-type fixnum = (handle-table-free ids) while (>= slot 0)
               do (setf (snap-u32 buffer (+ free-at (* 4 nfree))) slot)
                  (incf nfree)
                  (setf slot (aref locals slot)))
         (setf (snap-u32 buffer (+ at 4)) nfree)
         ;; the bodies added since the last step, each as its slot and generation
         (let ((added (physics-world-added world)) (n (physics-world-added-count world))
               (o (+ free-at (* 4 nfree))))
           (setf (snap-u32 buffer o) n)
           (dotimes (k n)
             (setf (snap-u32 buffer (+ o 4 (* 8 k))) (handle-index (aref added k))
                   (snap-u32 buffer (+ o 8 (* 8 k))) (handle-generation (aref added k))))
           (- (+ o 4 (* 8 n)) at))))
    (3 (write-snapshot-bodies (physics-world-awake world) buffer at (snapshot-scratch-materials scratch) 0
                              (snapshot-scratch-count scratch)))
    (4 (write-snapshot-bodies (physics-world-sleeping world) buffer at (snapshot-scratch-materials scratch)
                              (body-columns-length (physics-world-awake world)) (snapshot-scratch-count scratch)))
    (5 (let ((count (snapshot-scratch-count scratch)) (words (snapshot-scratch-palette scratch)))
         (setf (snap-u32 buffer at) count)
         (dotimes (k count)
           (dotimes (j 9)
             (setf (snap-u32 buffer (+ at 4 (* k +snapshot-material-bytes+) (* 4 j))) (aref words (+ (* 9 k) j)))))
         (+ 4 (* count +snapshot-material-bytes+))))
    (6 (write-snapshot-contacts world buffer at scratch))
    (7 (write-snapshot-pair-list world buffer at))
    (8 (let* ((boxes (physics-world-boxes world)) (n (box-columns-length boxes)))
         (setf (snap-u32 buffer at) n)
         (with-box-columns (min-x min-y min-z max-x max-y max-z vx vy vz (bid id) filter) boxes
           (dotimes (row n)
             (let ((o (+ at 4 (* row +snapshot-box-bytes+))))
               (macrolet ((floats (&rest columns)
                            `(setf ,@(loop for c in columns for k from 0
                                           append `((snap-f32 buffer (+ o ,(* 4 k))) (aref ,c row))))))
                 (floats min-x min-y min-z max-x max-y max-z vx vy vz))
               (setf (snap-i64 buffer (+ o 36)) (aref bid row) (snap-i64 buffer (+ o 44)) (aref filter row)))))
         (+ 4 (* n +snapshot-box-bytes+))))
    (9 (let ((pushes (physics-world-pushes world)))
         (if pushes
             (let ((slots (handle-table-count (physics-world-ids world))))
               (setf (snap-u32 buffer at) slots)
               (sb-kernel:%byte-blt pushes 0 buffer (+ at 4) (+ at 4 (* 16 slots)))
               (+ 4 (* 16 slots)))
             (progn (setf (snap-u32 buffer at) 0) 4))))
    (10 (write-snapshot-joints world buffer at)
        (aref (snapshot-scratch-sizes scratch) 10))
    (11 (write-snapshot-box-bodies world buffer at))))
;; Taking a snapshot: a bound, then each part in its order:2 ends here

;; [[file:../physics.org::#SNWBOD][The bodies, a column at a time, their materials in a palette:1]]
;;; the palette of materials: what a body was given when it was added, shared by many bodies

(defun material-words (bodies row words at)
  "Write into WORDS from AT the nine words of the material of ROW of BODIES: the bits of its
radius, inverse mass, inverse inertia, restitution, friction, rolling resistance and life, its
kind, and its filter (the flags from bit 16). #SNWBOD"
  (declare (type body-columns bodies) (type index row at) (type fixnum-column words) #.+kernel-policy+)
  (with-body-columns (radius inverse-mass inverse-inertia restitution friction rolling-resistance life kind flags)
      bodies
    (macrolet ((bits (column) `(ldb (byte 32 0) (sb-kernel:single-float-bits (aref ,column row)))))
      (setf (aref words at) (bits radius) (aref words (+ at 1)) (bits inverse-mass)
            (aref words (+ at 2)) (bits inverse-inertia) (aref words (+ at 3)) (bits restitution)
            (aref words (+ at 4)) (bits friction) (aref words (+ at 5)) (bits rolling-resistance)
            (aref words (+ at 6)) (bits life) (aref words (+ at 7)) (ldb (byte 32 0) (aref kind row))
            (aref words (+ at 8)) (ldb (byte 32 0) (ash (aref flags row) -16))))))

(defun palette-index (scratch bodies row)
  "The index in SCRATCH's palette of the material of ROW of BODIES, added when new. #SNWBOD"
  (declare (type snapshot-scratch scratch) (type body-columns bodies) (type index row) #.+kernel-policy+)
  (let ((count (snapshot-scratch-count scratch)))
    (when (> (* 9 (1+ count)) (length (snapshot-scratch-palette scratch)))
      (setf (snapshot-scratch-palette scratch)
            (replace (make-array (* 18 (1+ count)) :element-type 'fixnum) (snapshot-scratch-palette scratch))))
    ;; when the table is half full it doubles, and every entry is put in again
    (when (> (* 2 (1+ count)) (length (snapshot-scratch-table scratch)))
      (let ((table (make-array (* 2 (length (snapshot-scratch-table scratch))) :element-type 'fixnum
                                                                              :initial-element -1)))
        (setf (snapshot-scratch-table scratch) table)
        (dotimes (k count) (palette-place scratch k))))
    (let ((words (snapshot-scratch-palette scratch)) (at (* 9 count)))
      (material-words bodies row words at)
      (let ((place (palette-place scratch count)))
        (declare (type fixnum place))
        (when (= place count) (incf (snapshot-scratch-count scratch)))
        place))))

(defun palette-place (scratch k)
  "The palette index of the material whose nine words stand at entry K of SCRATCH's palette:
an earlier entry with the same words, found through the table, or K itself, then entered. #SNWBOD"
  (declare (type snapshot-scratch scratch) (type index k) #.+kernel-policy+)
  (let* ((words (snapshot-scratch-palette scratch)) (table (snapshot-scratch-table scratch))
         (mask (1- (length table))) (at (* 9 k)) (h 0))
    (declare (type fixnum-column words table) (type fixnum mask) (type (unsigned-byte 62) h))
    (dotimes (i 9) (setf h (ldb (byte 62 0) (+ (* h 1099511628211) (aref words (+ at i))))))
    (loop for i of-type fixnum = (logand (ash h -7) mask) then (logand (1+ i) mask)
          for e of-type fixnum = (aref table i)
          do (cond ((= e -1) (setf (aref table i) k) (return k))
                   ((loop for j below 9 always (= (aref words (+ (* 9 e) j)) (aref words (+ at j))))
                    (return e))))))

(declaim (inline same-material-p))
(defun same-material-p (bodies row other)
  "True when rows ROW and OTHER of BODIES have the same material, bit for bit: the nine words
material-words writes. #SNWBOD"
  (declare (type body-columns bodies) (type index row other) #.+kernel-policy+)
  (with-body-columns (radius inverse-mass inverse-inertia restitution friction rolling-resistance life kind flags)
      bodies
    (macrolet ((same (&rest columns)
                 `(and ,@(loop for c in columns
                               collect `(= (sb-kernel:single-float-bits (aref ,c row))
                                           (sb-kernel:single-float-bits (aref ,c other)))))))
      (and (same radius inverse-mass inverse-inertia restitution friction rolling-resistance life)
           (= (aref kind row) (aref kind other))
           (= (ldb (byte 32 16) (aref flags row)) (ldb (byte 32 16) (aref flags other)))))))

(defun snapshot-materials (world scratch)
  "Fill SCRATCH's palette with the materials of WORLD's bodies, awake rows then sleeping, and
its materials column with each body's entry; return the palette's size. #SNWBOD"
  (declare (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((awake (physics-world-awake world)) (sleeping (physics-world-sleeping world))
         (n (+ (body-columns-length awake) (body-columns-length sleeping))))
    (when (< (length (snapshot-scratch-materials scratch)) n)
      (setf (snapshot-scratch-materials scratch)
            (make-array (max n (* 2 (length (snapshot-scratch-materials scratch)))) :element-type 'fixnum)))
    (fill (snapshot-scratch-table scratch) -1)
    (setf (snapshot-scratch-count scratch) 0)
    (let ((materials (snapshot-scratch-materials scratch)) (k 0))
      (declare (type fixnum-column materials) (type index k))
      (flet ((walk (bodies)
               (declare (type body-columns bodies))
               (let ((last -1))
                 (declare (type fixnum last))
                 (dotimes (row (body-columns-length bodies))
                   ;; most bodies share the material of the row before them: compared, not hashed
                   (setf last (if (and (> row 0) (same-material-p bodies row (1- row)))
                                  last
                                  (palette-index scratch bodies row))
                         (aref materials k) last)
                   (incf k)))))
        (walk awake)
        (walk sleeping)))
    (snapshot-scratch-count scratch)))
;; The bodies, a column at a time, their materials in a palette:1 ends here

;; [[file:../physics.org::#SNWBOD][The bodies, a column at a time, their materials in a palette:2]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +snapshot-body-floats+ '(x y z vx vy vz wx wy wz qw qx qy qz sleep-time)
    "The single-float columns of a body that a body part of a snapshot holds, each as one block of
its rows, in this order. #SNWBOD"))

(defmacro do-snapshot-body-floats ((column k) bodies &body body)
  "Run BODY once for each column of +snapshot-body-floats+, COLUMN bound to that column of BODIES
and K to its place in the list, written out, not looped over. #SNWBOD"
  (let ((b (gensym "BODIES")))
    `(let ((,b ,bodies))
       ,@(loop for c in +snapshot-body-floats+ for i from 0
               collect `(let ((,column (,(intern (format nil "BODY-COLUMNS-~A" c) (symbol-package 'body-columns-x)) ,b)))
                          (declare (type f32-column ,column) (ignorable ,column))
                          (symbol-macrolet ((,k ,i)) ,@body))))))

(declaim (inline body-part-column))
(defun body-part-column (n k &optional (width 4))
  "Where, from the count that starts a body part of N bodies, the block of its K-th column begins:
the float columns of +snapshot-body-floats+ from 0, then age (14, two units), slot (16) and
material (17), in 4-byte units, and the flags (18) after the materials' indices of WIDTH bytes
each. #SNWBOD"
  (declare (type index n) (type (integer 0 18) k) (type (member 1 2 4) width))
  (the index (if (= k 18) (+ 4 (* (+ 68 width) n)) (+ 4 (* 4 k n)))))

(declaim (inline snap-material-index (setf snap-material-index)))
(defun snap-material-index (buffer offset width)
  "The material index of WIDTH bytes at OFFSET of BUFFER. #SNWBOD"
  (declare (type octets buffer) (type index offset) (type (member 1 2 4) width))
  (case width (1 (snap-u8 buffer offset)) (2 (snap-u16 buffer offset)) (t (snap-u32 buffer offset))))

(defun (setf snap-material-index) (value buffer offset width)
  "Write the material index VALUE in WIDTH bytes at OFFSET of BUFFER. #SNWBOD"
  (declare (type octets buffer) (type index offset) (type (member 1 2 4) width) (type (unsigned-byte 32) value))
  (case width
    (1 (setf (snap-u8 buffer offset) value))
    (2 (setf (snap-u16 buffer offset) value))
    (t (setf (snap-u32 buffer offset) value))))

(defun write-snapshot-bodies (bodies buffer at materials first palette)
  "Write the rows of BODIES into BUFFER from AT: their count, then each column as one block of
every row's value, the float columns and the ages copied whole, the row's material being entry
FIRST + row of MATERIALS, an index into a PALETTE of that many entries; return the padded bytes
written. #SNWBOD"
  (declare (type body-columns bodies) (type octets buffer) (type index at first palette)
           (type fixnum-column materials) #.+kernel-policy+)
  (let ((n (body-columns-length bodies)) (w (material-index-bytes palette)))
    (setf (snap-u32 buffer at) n)
    (do-snapshot-body-floats (column k) bodies
      (sb-kernel:%byte-blt column 0 buffer (+ at (body-part-column n k)) (+ at (body-part-column n (1+ k)))))
    (sb-kernel:%byte-blt (body-columns-age bodies) 0 buffer (+ at (body-part-column n 14)) (+ at (body-part-column n 16)))
    (let ((handle (body-columns-handle bodies)) (flags (body-columns-flags bodies))
          (s (+ at (body-part-column n 16))) (m (+ at (body-part-column n 17))) (f (+ at (body-part-column n 18 w))))
      (declare (type fixnum-column handle flags) (type index s m f))
      (dotimes (row n)
        (setf (snap-u32 buffer (+ s (* 4 row))) (ldb (byte +handle-index-bits+ 0) (aref handle row))
              (snap-material-index buffer (+ m (* w row)) w) (aref materials (+ first row))
              (snap-u16 buffer (+ f (* 2 row))) (ldb (byte 16 0) (aref flags row))))
      ;; the padding reads as zeros
      (loop for p of-type index from (+ f (* 2 n)) below (+ at (padded (+ 4 (* (body-record-bytes palette) n))))
            do (setf (aref buffer p) 0)))
    (padded (+ 4 (* (body-record-bytes palette) n)))))
;; The bodies, a column at a time, their materials in a palette:2 ends here

;; [[file:../physics.org::#SNWCON][The contacts: keys copied whole, the rest in five streams:1]]
(declaim (inline normal-code))
(defun normal-code (x y z)
  "The code of the normal whose components have the bits X Y Z: 1 to 6 for the unit vectors +x
-x +y -y +z -z, exactly, and 0 for any other. #SNWCON"
  (declare (type (unsigned-byte 32) x y z))
  ;; the bits of 1.0 and of -1.0
  (flet ((code (v plus minus)
           (declare (type (unsigned-byte 32) v) (type fixnum plus minus))
           (cond ((= v #x3F800000) plus) ((= v #xBF800000) minus) (t 0))))
    (declare (inline code))
    (cond ((zerop (logior y z)) (code x 1 2))
          ((zerop (logior x z)) (code y 3 4))
          ((zerop (logior x y)) (code z 5 6))
          (t 0))))

(defun snapshot-stream-room (scratch n)
  "SCRATCH's stream words, with room for N + 1 entries of each stream (ten words a contact). #SNWCON"
  (declare (type snapshot-scratch scratch) (type index n))
  (let ((words (* 10 (1+ n))))
    (when (< (length (snapshot-scratch-streams scratch)) words)
      (setf (snapshot-scratch-streams scratch)
            (make-array (max words (* 2 (length (snapshot-scratch-streams scratch)))) :element-type '(unsigned-byte 32))))
    (snapshot-scratch-streams scratch)))

(defun write-snapshot-contact-flags (world buffer at streams)
  "One pass over WORLD's contacts in their row order: each one's flags into the contact part at AT
of BUFFER, and its words into each stream it belongs to, stream K's entries from word (N + 1)
times the widths before K of STREAMS, its entry past the last zero; each stream's count into the
part's head. #SNWCON"
  (declare (type octets buffer) (type index at) (type (simple-array (unsigned-byte 32) (*)) streams)
           #.+kernel-policy+)
  (let* ((contacts (physics-world-contacts world)) (n (contact-columns-length contacts)) (m (1+ n))
         (step (physics-world-step-count world)))
    (declare (type index n m) (type fixnum step))
    (with-contact-columns (seen touching geometry) contacts
      (sb-sys:with-pinned-objects (geometry streams buffer)
        ;; pointers that move on: a field is then one load at a fixed displacement
        (let ((g (sb-sys:vector-sap geometry))
              (f (sb-sys:sap+ (sb-sys:vector-sap buffer) (+ at +snapshot-contact-head-bytes+ (* 8 n))))
              (s0 (sb-sys:vector-sap streams)) (s1 (sb-sys:sap+ (sb-sys:vector-sap streams) (* 12 m)))
              (s2 (sb-sys:sap+ (sb-sys:vector-sap streams) (* 16 m))) (s3 (sb-sys:sap+ (sb-sys:vector-sap streams) (* 24 m)))
              (s4 (sb-sys:sap+ (sb-sys:vector-sap streams) (* 36 m))))
          (macrolet ((word (k) `(sb-sys:sap-ref-32 g ,(* 4 k)))
                     (put (s width first present)
                       ;; the words go in at the stream's end, which moves on only when present
                       `(progn ,@(loop for k below width collect `(setf (sb-sys:sap-ref-32 ,s ,(* 4 k)) (word ,(+ first k))))
                               (setf ,s (sb-sys:sap+ ,s (* ,(* 4 width) ,present))))))
            (dotimes (row n)
              (let* ((code (normal-code (word 0) (word 1) (word 2)))
                     (p0 (if (zerop code) 1 0))
                     (p1 (if (zerop (word #.(position 'normal-impulse +contact-fields+))) 0 1))
                     (p2 (if (zerop (logior (word #.(position 'tangent-impulse-1 +contact-fields+))
                                            (word #.(1+ (position 'tangent-impulse-1 +contact-fields+)))))
                             0 1))
                     (p3 (if (zerop (logior (word #.(position 'rolling-impulse-x +contact-fields+))
                                            (word #.(+ 1 (position 'rolling-impulse-x +contact-fields+)))
                                            (word #.(+ 2 (position 'rolling-impulse-x +contact-fields+)))))
                             0 1))
                     (p4 (if (zerop (word #.(position 'spin-impulse +contact-fields+))) 0 1)))
                (declare (type (integer 0 6) code) (type bit p0 p1 p2 p3 p4))
                (setf (sb-sys:sap-ref-16 f 0)
                      (logior (if (= 1 (aref touching row)) 1 0) (if (= step (aref seen row)) 0 2) (ash code 2)
                              (ash p1 5) (ash p2 6) (ash p3 7) (ash p4 8)))
                (put s0 3 0 p0)
                (put s1 1 #.(position 'normal-impulse +contact-fields+) p1)
                (put s2 2 #.(position 'tangent-impulse-1 +contact-fields+) p2)
                (put s3 3 #.(position 'rolling-impulse-x +contact-fields+) p3)
                (put s4 1 #.(position 'spin-impulse +contact-fields+) p4)
                (setf g (sb-sys:sap+ g #.(* 4 (length +contact-fields+))) f (sb-sys:sap+ f 2)))))
          ;; each stream's count, and its entry past the last, zeros
          (let ((base (sb-sys:vector-sap streams)))
            (macrolet ((close-stream (s k start width)
                         `(let ((count (floor (- (sb-sys:sap-int ,s) (sb-sys:sap-int base) ,(* 4 start) (* ,(* 4 start) n))
                                              ,(* 4 width))))
                            (dotimes (j ,width) (setf (sb-sys:sap-ref-32 ,s (* 4 j)) 0))
                            (setf (snap-u32 buffer (+ at ,(+ 4 (* 4 k)))) count))))
              (close-stream s0 0 0 3) (close-stream s1 1 3 1) (close-stream s2 2 4 2)
              (close-stream s3 3 6 3) (close-stream s4 4 9 1))))))))

(defun write-snapshot-contacts (world buffer at scratch)
  "Write the contacts of WORLD into BUFFER from AT as columns: their count and the counts of the
five streams, the keys (the key column's words, copied whole), each contact's flags, then the
streams, each closed by an entry of zeros; return the padded bytes written. #SNWCON"
  (declare (type octets buffer) (type index at) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((contacts (physics-world-contacts world)) (n (contact-columns-length contacts)) (m (1+ n))
         (streams (snapshot-stream-room scratch n))
         (keys (+ at +snapshot-contact-head-bytes+)) (o (+ keys (* 10 n))))
    (declare (type index n m keys o) (type (simple-array (unsigned-byte 32) (*)) streams))
    (setf (snap-u32 buffer at) n)
    (sb-kernel:%byte-blt (contact-columns-key contacts) 0 buffer keys (+ keys (* 8 n)))
    (write-snapshot-contact-flags world buffer at streams)
    ;; each stream's entries and its closing zeros, copied whole
    (loop for (start width) in '((0 3) (3 1) (4 2) (6 3) (9 1))
          for k from 0
          do (let ((bytes (* 4 width (1+ (snap-u32 buffer (+ at 4 (* 4 k)))))))
               (declare (type index bytes))
               (sb-kernel:%byte-blt streams (* 4 start m) buffer o (+ o bytes))
               (incf o bytes)))
    (loop while (logtest o 3) do (setf (aref buffer o) 0) (incf o))
    (- o at)))
;; The contacts: keys copied whole, the rest in five streams:1 ends here

;; [[file:../physics.org::#SNWPAR][The pair list and the world part:1]]
(defun write-snapshot-pair-list (world buffer at)
  "Write the pair list of WORLD into BUFFER from AT: its numbers, each row's anchor, the rows'
clear marks as bits, the rows' handles unless they are the awake rows' own, and the pairs as
differences of rows when they fit in a byte and a 16-bit word, else whole; return the padded
bytes written. #SNWPAR"
  (declare (type octets buffer) (type index at) #.+kernel-policy+)
  (let* ((plist (physics-world-pair-list world)) (rows (pair-list-rows plist))
         (n (max rows 0)) (pairs (if (>= rows 0) (pair-list-count plist) 0))
         (awake (physics-world-awake world)) (handles (pair-list-handles plist))
         (own (and (<= n (body-columns-length awake))
                   (let ((now (body-columns-handle awake)))
                     (declare (type fixnum-column now))
                     (loop for i of-type index below n always (= (aref handles i) (aref now i))))))
         (o (+ at +snapshot-pair-head-bytes+ (* +snapshot-pair-row-bytes+ n))))
    (declare (type fixnum rows) (type index n pairs o))
    (setf (snap-i32 buffer at) rows (snap-f32 buffer (+ at 4)) (pair-list-cell plist)
          (snap-u32 buffer (+ at 8)) (pair-list-builds plist) (snap-i32 buffer (+ at 12)) (pair-list-loose-count plist)
          (snap-i64 buffer (+ at 16)) (pair-list-step plist) (snap-i64 buffer (+ at 24)) (pair-list-built-step plist)
          (snap-u32 buffer (+ at 32)) pairs)
    (sb-kernel:%byte-blt (pair-list-anchors plist) 0 buffer (+ at +snapshot-pair-head-bytes+) o)
    ;; the clear marks, a bit a row in 32-bit words
    (let ((clear (pair-list-clear plist)))
      (declare (type fixnum-column clear))
      (dotimes (w (ceiling n 32))
        (let ((word 0))
          (declare (type (unsigned-byte 32) word))
          (loop for i of-type index from (* 32 w) below (min n (* 32 (1+ w)))
                do (when (= 1 (aref clear i)) (setf word (logior word (ash 1 (- i (* 32 w)))))))
          (setf (snap-u32 buffer o) word)
          (incf o 4))))
    (unless own
      (dotimes (i n) (setf (snap-i64 buffer o) (aref handles i)) (incf o 8)))
    (let ((list (pair-list-pairs plist)) (deltas t))
      (declare (type fixnum-column list))
      ;; as deltas: a byte a pair, its row A less the pair before's, signed, or -128 when that does
      ;; not fit and A is the next of the rows listed whole after; then a 16-bit word a pair, its row
      ;; B less its row A, signed; whole pairs when some B - A does not fit
      (let ((whole (padded (+ o (* 3 pairs)))) (wholes 0))
        (declare (type index whole wholes))
        (loop with last of-type fixnum = 0
              for k of-type index below pairs
              for a of-type fixnum = (ash (aref list k) -24)
              for b of-type fixnum = (ldb (byte 24 0) (aref list k))
              do (unless (<= -32768 (- b a) 32767) (return (setf deltas nil)))
                 (if (< -128 (- a last) 128)
                     (setf (snap-u8 buffer (+ o k)) (ldb (byte 8 0) (- a last)))
                     (setf (snap-u8 buffer (+ o k)) 128
                           (snap-u32 buffer (+ whole 4 (* 4 wholes))) a
                           wholes (1+ wholes)))
                 (setf (snap-u16 buffer (+ o pairs (* 2 k))) (ldb (byte 16 0) (- b a)) last a))
        (if deltas
            (progn (loop for q of-type index from (+ o (* 3 pairs)) below whole do (setf (aref buffer q) 0))
                   (setf (snap-u32 buffer whole) wholes o (+ whole 4 (* 4 wholes))))
            (dotimes (k pairs) (setf (snap-i64 buffer o) (aref list k)) (incf o 8))))
      (setf (snap-u32 buffer (+ at 36)) (logior (if own 0 1) (if deltas 2 0))))
    (loop while (logtest o 3) do (setf (aref buffer o) 0) (incf o))
    (- o at)))
;; The pair list and the world part:1 ends here

;; [[file:../physics.org::#SNWPAR][The pair list and the world part:3]]
(defun write-snapshot-world (world buffer at)
  "Write the world part of WORLD's snapshot into BUFFER from AT: its numbers, its parameters and
the last step's statistics. #SNWPAR"
  (declare (type octets buffer) (type index at) #.+kernel-policy+)
  (let ((stats (world-statistics world)) (terrain (physics-world-terrain world))
        (name (symbol-name (kernel-family-name (physics-world-kernels world)))))
    (setf (snap-u32 buffer at) (handle-table-tag (physics-world-ids world))
          (snap-u32 buffer (+ at 4)) (features-mask (world-features world))
          (snap-u32 buffer (+ at 8)) (logior (if (physics-world-sleep-enabled world) 1 0)
                                             (if (physics-world-filtering world) 2 0)
                                             (if (physics-world-column-watch world) 4 0)
                                             (if (physics-world-pushed world) 8 0))
          (snap-u32 buffer (+ at 12)) (physics-world-substeps world)
          (snap-u64 buffer (+ at 16)) (physics-world-step-count world)
          (snap-f32 buffer (+ at 24)) (physics-world-step-seconds world)
          (snap-f32 buffer (+ at 28)) (physics-world-gravity-x world)
          (snap-f32 buffer (+ at 32)) (physics-world-gravity-y world)
          (snap-f32 buffer (+ at 36)) (physics-world-gravity-z world)
          (snap-f32 buffer (+ at 40)) (physics-world-current-dt world)
          (snap-f32 buffer (+ at 44)) (physics-world-current-h world)
          (snap-f32 buffer (+ at 48)) (physics-world-max-radius world))
    (loop for (name nil nil nil kind) in +physics-parameters+
          for o of-type index from (+ at 52) by 4
          for value = (world-parameter world name)
          do (if (eq kind 'integer)
                 (setf (snap-u32 buffer o) value)
                 (setf (snap-f32 buffer o) value)))
    (setf (snap-i64 buffer (+ at 124)) (physics-world-braced-step world)
          (snap-i64 buffer (+ at 132)) (physics-world-awake-grid-step world)
          (snap-u64 buffer (+ at 140)) (contact-table-misses (physics-world-contact-table world))
          (snap-u32 buffer (+ at 148)) (step-statistics-contacts stats)
          (snap-u32 buffer (+ at 152)) (step-statistics-colors stats)
          (snap-f64 buffer (+ at 156)) (step-statistics-real-seconds stats)
          (snap-f64 buffer (+ at 164)) (step-statistics-max-penetration stats)
          (snap-f64 buffer (+ at 172)) (step-statistics-max-approach stats)
          (snap-u64 buffer (+ at 180)) (if terrain (voxel-terrain-edits terrain) 0))
    (dotimes (i (min 16 (length name)))
      (setf (snap-u8 buffer (+ at 188 i)) (logand 127 (char-code (char name i)))))))

(defun world-parameter (world name)
  "The value of WORLD's parameter NAME, a keyword of +physics-parameters+. #SNWPAR"
  (ecase name
    (:contact-hertz (physics-world-contact-hertz world))
    (:contact-damping-ratio (physics-world-damping-ratio world))
    (:contact-push-max (physics-world-push-max world))
    (:load-stiffening (physics-world-load-stiffening world))
    (:crowded-relax-passes (physics-world-crowded-relax-passes world))
    (:crowded-depth (physics-world-crowded-depth world))
    (:linear-slop (physics-world-slop world))
    (:speculative-margin (physics-world-margin world))
    (:pair-skin (physics-world-pair-skin world))
    (:restitution-threshold (physics-world-restitution-threshold world))
    (:hit-speed (physics-world-hit-speed world))
    (:sleep-speed (physics-world-sleep-speed world))
    (:time-to-sleep (physics-world-time-to-sleep world))
    (:wake-speed (physics-world-wake-speed world))
    (:brace-mass-ratio (physics-world-brace-mass-ratio world))
    (:reach-limit (physics-world-reach-limit world))
    (:max-speed (physics-world-max-speed world))
    (:body-budget (physics-world-body-budget world))))

(defun (setf world-parameter) (value world name)
  "Set WORLD's parameter NAME, a keyword of +physics-parameters+, to VALUE. #SNWPAR"
  (ecase name
    (:contact-hertz (setf (physics-world-contact-hertz world) value))
    (:contact-damping-ratio (setf (physics-world-damping-ratio world) value))
    (:contact-push-max (setf (physics-world-push-max world) value))
    (:load-stiffening (setf (physics-world-load-stiffening world) value))
    (:crowded-relax-passes (setf (physics-world-crowded-relax-passes world) value))
    (:crowded-depth (setf (physics-world-crowded-depth world) value))
    (:linear-slop (setf (physics-world-slop world) value))
    (:speculative-margin (setf (physics-world-margin world) value))
    (:pair-skin (setf (physics-world-pair-skin world) value))
    (:restitution-threshold (setf (physics-world-restitution-threshold world) value))
    (:hit-speed (setf (physics-world-hit-speed world) value))
    (:sleep-speed (setf (physics-world-sleep-speed world) value))
    (:time-to-sleep (setf (physics-world-time-to-sleep world) value))
    (:wake-speed (setf (physics-world-wake-speed world) value))
    (:brace-mass-ratio (setf (physics-world-brace-mass-ratio world) value))
    (:reach-limit (setf (physics-world-reach-limit world) value))
    (:max-speed (setf (physics-world-max-speed world) value))
    (:body-budget (setf (physics-world-body-budget world) value))))
;; The pair list and the world part:3 ends here

;; [[file:../physics.org::#SNCHCK][Bad bytes: every byte checked before any is written:1]]
(define-condition physics-snapshot-invalid (physics-error)
  ((operation :initarg :operation :reader physics-snapshot-invalid-operation)
   (offset :initarg :offset :reader physics-snapshot-invalid-offset)
   (expected :initarg :expected :reader physics-snapshot-invalid-expected)
   (found :initarg :found :reader physics-snapshot-invalid-found))
  (:report (lambda (c s)
             (format s "~(~A~): the snapshot is refused at byte ~D: expected ~A, found ~S; the world is unchanged"
                     (physics-snapshot-invalid-operation c) (physics-snapshot-invalid-offset c)
                     (physics-snapshot-invalid-expected c) (physics-snapshot-invalid-found c))))
  (:documentation "A snapshot that cannot be restored, naming the operation, the byte offset, what
was expected there and what was found; the world restored into is left as it was. #SNCHCK"))

(define-condition physics-snapshot-truncated (physics-snapshot-invalid) ()
  (:documentation "A snapshot shorter than its header or its recorded size. #SNCHCK"))

(define-condition physics-snapshot-wrong-magic (physics-snapshot-invalid) ()
  (:documentation "Bytes that do not start with the snapshot magic LUVWORLD. #SNCHCK"))

(define-condition physics-snapshot-wrong-version (physics-snapshot-invalid) ()
  (:documentation "A snapshot of a layout version this engine does not read. #SNCHCK"))

(define-condition physics-snapshot-checksum-mismatch (physics-snapshot-invalid) ()
  (:documentation "A snapshot whose bytes do not hash to its recorded checksum. #SNCHCK"))

(define-condition physics-snapshot-other-layout (physics-snapshot-invalid) ()
  (:documentation "A snapshot whose parts, counts or values do not describe a world this engine
can hold: parts out of order or of the wrong size, a slot out of range, a number out of its
range, a body in a solid cell. #SNCHCK"))

(define-condition physics-snapshot-missing-features (physics-snapshot-invalid) ()
  (:documentation "A snapshot of a world that used a feature the target world was made without. #SNCHCK"))

(defun snapshot-refuse (type operation offset expected found)
  "Signal the physics-snapshot-invalid subtype TYPE. #SNCHCK"
  (error type :operation operation :offset offset :expected expected :found found))
;; Bad bytes: every byte checked before any is written:1 ends here

;; [[file:../physics.org::#SNCHCK][Bad bytes: every byte checked before any is written:2]]
;;; reading a snapshot back: every byte is checked before the world is touched

(defmacro snapshot-check (test type offset expected found)
  "Unless TEST, refuse the snapshot (a restore's) with the physics-snapshot-invalid subtype TYPE at
OFFSET. #SNCHCK"
  `(unless ,test (snapshot-refuse ',type 'restore-physics-world ,offset ,expected ,found)))

(declaim (inline snap-finite-f32 snap-finite-f64))
(defun snap-finite-f32 (buffer offset)
  "The single-float at OFFSET of BUFFER, or the snapshot refused there when it is not finite. #SNCHCK"
  (declare (type octets buffer) (type index offset))
  (let ((bits (snap-u32 buffer offset)))
    (snapshot-check (/= (ldb (byte 8 23) bits) 255) physics-snapshot-other-layout offset
                    "a finite single-float" bits)
    (snap-f32 buffer offset)))

(defun snap-finite-f64 (buffer offset)
  "The double-float at OFFSET of BUFFER, or the snapshot refused there when it is not finite. #SNCHCK"
  (declare (type octets buffer) (type index offset))
  (let ((bits (snap-u64 buffer offset)))
    (snapshot-check (/= (ldb (byte 11 52) bits) 2047) physics-snapshot-other-layout offset
                    "a finite double-float" bits)
    (snap-f64 buffer offset)))

(defun check-snapshot (world buffer scratch)
  "Check every byte of the snapshot BUFFER for restoring into WORLD, signalling the
physics-snapshot-invalid subtype that names the first fault and its byte offset; leave in SCRATCH
what the restore reuses. #SNCHCK"
  (check-snapshot-frame buffer scratch)
  (check-snapshot-world world buffer scratch)
  (check-snapshot-slots world buffer scratch)
  (check-snapshot-contacts world buffer scratch)
  (check-snapshot-pair-list buffer scratch)
  (check-snapshot-rest buffer scratch)
  (check-snapshot-joints buffer scratch)
  (check-snapshot-box-bodies buffer scratch)
  buffer)
;; Bad bytes: every byte checked before any is written:2 ends here

;; [[file:../physics.org::#SNCHCK][Bad bytes: every byte checked before any is written:3]]
(defun check-snapshot-frame (buffer scratch)
  "Check BUFFER's header, checksum and part frames; note each part's payload offset and size in
SCRATCH by part id; return the snapshot's size. #SNCHCK"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (let ((length (length buffer)))
    (snapshot-check (>= length +snapshot-header-bytes+) physics-snapshot-truncated length
                    (format nil "a header of ~D bytes" +snapshot-header-bytes+) length)
    (let ((wrong (mismatch buffer +snapshot-magic+ :end1 8)))
      (snapshot-check (null wrong) physics-snapshot-wrong-magic wrong "the magic LUVWORLD" (subseq buffer 0 8)))
    (snapshot-check (= (snap-u32 buffer 8) +snapshot-version+) physics-snapshot-wrong-version 8
                    (format nil "version ~D" +snapshot-version+) (snap-u32 buffer 8))
    (let ((total (snap-u64 buffer 16)))
      (snapshot-check (<= total length) physics-snapshot-truncated length
                      (format nil "the ~D bytes the header records" total) length)
      (snapshot-check (and (>= total +snapshot-header-bytes+) (zerop (mod (- total +snapshot-header-bytes+) 4)))
                      physics-snapshot-other-layout 16 "a size past the header, by whole words" total)
      (let ((sum (snapshot-checksum buffer +snapshot-header-bytes+ total)))
        (snapshot-check (= sum (snap-u64 buffer 24)) physics-snapshot-checksum-mismatch 24
                        (format nil "the checksum of the bytes, ~D" sum) (snap-u64 buffer 24)))
      (let ((at +snapshot-header-bytes+) (present 0))
        (declare (type index at present))
        (loop for (id name optional) in +snapshot-parts+
              ;; an optional part the world did not have is not there: its size is -1
              if (and optional (or (> (+ at 8) total) (/= (snap-u32 buffer at) id)))
                do (setf (aref (snapshot-scratch-offsets scratch) id) 0 (aref (snapshot-scratch-sizes scratch) id) -1)
              else
              do (incf present)
                 (snapshot-check (<= (+ at 8) total) physics-snapshot-other-layout at
                                 (format nil "the ~(~A~) part" name) :end)
                 (snapshot-check (= (snap-u32 buffer at) id) physics-snapshot-other-layout at
                                 (format nil "the ~(~A~) part, id ~D" name id) (snap-u32 buffer at))
                 (let ((size (snap-u32 buffer (+ at 4))))
                   (snapshot-check (and (<= (+ at 8 size) total) (zerop (mod size 4)) (>= size 4))
                                   physics-snapshot-other-layout (+ at 4)
                                   (format nil "a size in words within the snapshot for the ~(~A~) part" name) size)
                   (setf (aref (snapshot-scratch-offsets scratch) id) (+ at 8)
                         (aref (snapshot-scratch-sizes scratch) id) size)
                   (incf at (+ 8 size))))
        (snapshot-check (= at total) physics-snapshot-other-layout at "the end of the snapshot" at)
        (snapshot-check (= (snap-u32 buffer 12) present) physics-snapshot-other-layout 12
                        (format nil "~D parts" present) (snap-u32 buffer 12)))
      total)))

(defun check-part-size (scratch id expected)
  "Refuse the snapshot unless part ID's payload, as SCRATCH noted it, is EXPECTED bytes. #SNCHCK"
  (declare (type snapshot-scratch scratch))
  (let ((size (aref (snapshot-scratch-sizes scratch) id)))
    (snapshot-check (= size expected) physics-snapshot-other-layout (- (aref (snapshot-scratch-offsets scratch) id) 4)
                    (format nil "~D bytes for part ~D as its counts give" expected id) size)))
;; Bad bytes: every byte checked before any is written:3 ends here

;; [[file:../physics.org::#SNCHCK][Bad bytes: every byte checked before any is written:4]]
(defun check-snapshot-world (world buffer scratch)
  "Check the world part of the snapshot in BUFFER against WORLD: its features within WORLD's, its
sleep, and every number within its range. #SNCHCK"
  (declare (type octets buffer))
  (check-part-size scratch 1 +snapshot-world-bytes+)
  (let* ((at (aref (snapshot-scratch-offsets scratch) 1))
         (mask (snap-u32 buffer (+ at 4)))
         (own (features-mask (world-features world))))
    (snapshot-check (zerop (logandc2 mask own)) physics-snapshot-missing-features (+ at 4)
                    (format nil "only features of the target world, ~{~S~^ ~}" (world-features world))
                    (loop for f in +physics-features+ for k from 0 when (logbitp k mask) collect f))
    (snapshot-check (eq (logbitp 0 (snap-u32 buffer (+ at 8))) (and (physics-world-sleep-enabled world) t))
                    physics-snapshot-other-layout (+ at 8)
                    (format nil "a world ~:[without~;with~] sleep, as the target is" (physics-world-sleep-enabled world))
                    (snap-u32 buffer (+ at 8)))
    (snapshot-check (<= 1 (snap-u32 buffer (+ at 12)) 64) physics-snapshot-other-layout (+ at 12)
                    "1 to 64 substeps" (snap-u32 buffer (+ at 12)))
    (snapshot-check (<= (snap-u64 buffer (+ at 16)) most-positive-fixnum) physics-snapshot-other-layout (+ at 16)
                    "a step count" (snap-u64 buffer (+ at 16)))
    (snapshot-check (< 0 (snap-u32 buffer at) (ash 1 +handle-tag-bits+)) physics-snapshot-other-layout at
                    "a world tag from 1 to 2^16 - 1" (snap-u32 buffer at))
    (flet ((ranged (offset low high what &optional name)
             (let ((v (snap-finite-f32 buffer offset)))
               (snapshot-check (<= low v high) physics-snapshot-other-layout offset
                               (if name (format nil "~(~A~) from ~A to ~A" name low high) what) v))))
      (ranged (+ at 24) +physics-min-step-seconds+ 0.99999994 "a step of under 1 second")
      (dotimes (k 3) (ranged (+ at 28 (* 4 k)) (- +physics-max-gravity+) +physics-max-gravity+ "a gravity in range"))
      (ranged (+ at 40) 1e-9 1.0 "the last step's length")
      (ranged (+ at 44) 1e-9 1.0 "the last substep's length")
      (loop for (name nil low high kind) in +physics-parameters+
            for o from (+ at 52) by 4
            do (if (eq kind 'integer)
                   (snapshot-check (<= low (snap-u32 buffer o) high) physics-snapshot-other-layout o
                                   (format nil "~(~A~) from ~D to ~D" name low high) (snap-u32 buffer o))
                   (ranged o low high nil name)))
      (let ((margin (snap-f32 buffer (+ at 52 (* 4 (position :speculative-margin +physics-parameters+ :key #'first)))))
            (limit (snap-f32 buffer (+ at 52 (* 4 (position :reach-limit +physics-parameters+ :key #'first))))))
        (snapshot-check (>= limit (+ margin +physics-min-radius+)) physics-snapshot-other-layout (+ at 52)
                        "a reach limit of at least the margin and the smallest radius" limit)
        ;; a box's half diagonal is its radius: the bound is the half diagonal of the largest box
        (ranged (+ at 48) 0.0 (box-half-diagonal +physics-max-radius+ +physics-max-radius+ +physics-max-radius+)
                "the largest radius the world has had, within the largest box's half diagonal")))
    (dolist (o '(124 132))
      (snapshot-check (typep (snap-i64 buffer (+ at o)) 'fixnum) physics-snapshot-other-layout (+ at o)
                      "a step number" (snap-i64 buffer (+ at o))))
    (snapshot-check (typep (snap-u64 buffer (+ at 140)) 'index) physics-snapshot-other-layout (+ at 140)
                    "a count of misses" (snap-u64 buffer (+ at 140)))
    ;; the statistics are read as single-floats too: a finite double beyond one's range is refused
    (dolist (o '(156 164 172))
      (snapshot-check (<= (abs (snap-finite-f64 buffer (+ at o))) 1d30) physics-snapshot-other-layout (+ at o)
                      "a statistic of magnitude up to 1e30" (snap-f64 buffer (+ at o))))))
;; Bad bytes: every byte checked before any is written:4 ends here

;; [[file:../physics.org::#SNCHCK][Bad bytes: every byte checked before any is written:5]]
(defun check-snapshot-handles (buffer scratch)
  "Check the handle part of the snapshot in BUFFER: its size as its counts give it, every
generation, every added body and every free slot within the table, each free slot listed once;
return SCRATCH's marks with the free slots marked, and the stamp that marks them. #SNCHCK"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((hat (aref (snapshot-scratch-offsets scratch) 2)) (count (snap-u32 buffer hat)) (nfree (snap-u32 buffer (+ hat 4))))
    (declare (type index hat) (type (unsigned-byte 32) count nfree))
    (snapshot-check (< count (ash 1 +handle-index-bits+)) physics-snapshot-other-layout hat
                    "a handle table of under 2^24 slots" count)
    (snapshot-check (<= nfree count) physics-snapshot-other-layout (+ hat 4) "no more free slots than slots" nfree)
    (let* ((o (+ hat 8 (* 4 count) (* 4 nfree))) (added (if (< (+ o 4) (length buffer)) (snap-u32 buffer o) 0)))
      (check-part-size scratch 2 (+ 12 (* 4 count) (* 4 nfree) (* 8 added)))
      (dotimes (k added)
        (snapshot-check (and (< (snap-u32 buffer (+ o 4 (* 8 k))) count)
                             (< (snap-u32 buffer (+ o 8 (* 8 k))) (ash 1 +handle-generation-bits+)))
                        physics-snapshot-other-layout (+ o 4 (* 8 k)) "an added body's slot and generation"
                        (snap-u32 buffer (+ o 4 (* 8 k))))))
    (dotimes (slot count)
      (snapshot-check (< (snap-u32 buffer (+ hat 8 (* 4 slot))) (ash 1 +handle-generation-bits+))
                      physics-snapshot-other-layout (+ hat 8 (* 4 slot)) "a generation under 2^20"
                      (snap-u32 buffer (+ hat 8 (* 4 slot)))))
    (multiple-value-bind (marks stamp) (snapshot-marks scratch count)
      (declare (type fixnum-column marks) (type fixnum stamp))
      (dotimes (k nfree)
        (let* ((o (+ hat 8 (* 4 count) (* 4 k))) (slot (snap-u32 buffer o)))
          (snapshot-check (and (< slot count) (< (aref marks slot) stamp)) physics-snapshot-other-layout o
                          "a free slot of the table, listed once" slot)
          (setf (aref marks slot) stamp)))
      (values marks stamp))))

(defun check-snapshot-materials (buffer scratch)
  "Check the material part of the snapshot in BUFFER: its size, and each material's numbers
within their ranges, its radius up to the world's largest. #SNCHCK"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((mat (aref (snapshot-scratch-offsets scratch) 5)) (materials (snap-u32 buffer mat))
         (max-radius (snap-f32 buffer (+ (aref (snapshot-scratch-offsets scratch) 1) 48))))
    (declare (type index mat) (type (unsigned-byte 32) materials) (type single-float max-radius))
    (check-part-size scratch 5 (+ 4 (* +snapshot-material-bytes+ materials)))
    (dotimes (k materials)
      (let ((o (+ mat 4 (* k +snapshot-material-bytes+))))
        (flet ((ranged (field low high what)
                 (let ((v (snap-finite-f32 buffer (+ o (* 4 field)))))
                   (snapshot-check (<= low v high) physics-snapshot-other-layout (+ o (* 4 field)) what v))))
          (ranged 0 +physics-min-radius+ max-radius "a radius from the smallest to the world's largest")
          (ranged 1 (/ 0.999 +physics-max-mass+) (/ 1.001 +physics-min-mass+) "the inverse of a mass in range")
          (ranged 2 0.0 (/ 2.6 (* +physics-min-mass+ +physics-min-radius+ +physics-min-radius+))
                  "the inverse of an inertia in range")
          (ranged 3 0.0 1.0 "a restitution in [0, 1]")
          (ranged 4 0.0 +physics-max-friction+ "a friction in range")
          (ranged 5 0.0 +physics-max-friction+ "a rolling resistance in range")
          (ranged 6 0.0 1e30 "a life of 0 or more"))
        (snapshot-check (<= 0 (snap-i32 buffer (+ o 28)) 1000) physics-snapshot-other-layout (+ o 28)
                        "a kind from 0 to 1000" (snap-i32 buffer (+ o 28)))))))
;; Bad bytes: every byte checked before any is written:5 ends here

;; [[file:../physics.org::#SNCHBD][Checking the bodies on their bits:1]]
(defun refuse-snapshot-body (buffer at n row max-speed)
  "Refuse the snapshot in BUFFER at the first number of body ROW, of the N of the body part at AT,
that is not finite or not in its range, naming what was expected. #SNCHBD"
  (declare (type octets buffer) (type index at n row) (type single-float max-speed))
  (flet ((float-at (k) (+ at (body-part-column n k) (* 4 row))))
    (dotimes (k 14) (snap-finite-f32 buffer (float-at k)))
    (snap-finite-f64 buffer (+ at (body-part-column n 14) (* 8 row)))
    (dotimes (k 3)
      (let ((c (snap-f32 buffer (float-at k))))
        (snapshot-check (< (abs c) +physics-coordinate-limit+) physics-snapshot-other-layout (float-at k)
                        "a coordinate within the limit" c)))
    (let ((vx (snap-f32 buffer (float-at 3))) (vy (snap-f32 buffer (float-at 4))) (vz (snap-f32 buffer (float-at 5)))
          (qw (snap-f32 buffer (float-at 9))) (qx (snap-f32 buffer (float-at 10))) (qy (snap-f32 buffer (float-at 11)))
          (qz (snap-f32 buffer (float-at 12))))
      (snapshot-check (and (<= (abs vx) max-speed) (<= (abs vy) max-speed) (<= (abs vz) max-speed)
                           (<= (+ (* vx vx) (* vy vy) (* vz vz)) (* 1.001 max-speed max-speed)))
                      physics-snapshot-other-layout (float-at 3) "a speed within the world's top speed" vx)
      (loop for k from 6 below 9
            do (snapshot-check (<= (abs (snap-f32 buffer (float-at k))) 1e6) physics-snapshot-other-layout
                               (float-at k) "a spin under 10^6 rad/s" (snap-f32 buffer (float-at k))))
      (snapshot-check (and (<= (abs qw) 1.1) (<= (abs qx) 1.1) (<= (abs qy) 1.1) (<= (abs qz) 1.1)
                           (<= 0.9 (+ (* qw qw) (* qx qx) (* qy qy) (* qz qz)) 1.1))
                      physics-snapshot-other-layout (float-at 9) "a unit quaternion" qw))
    (snapshot-check (<= 0.0 (snap-f32 buffer (float-at 13)) 1e30) physics-snapshot-other-layout (float-at 13)
                    "a time still of 0 or more" (snap-f32 buffer (float-at 13)))
    (let ((age (+ at (body-part-column n 14) (* 8 row))))
      (snapshot-check (<= 0d0 (snap-f64 buffer age) 1d30) physics-snapshot-other-layout age
                      "an age of 0 or more" (snap-f64 buffer age)))))

(defun check-snapshot-body-columns (buffer at n max-speed)
  "Refuse the body part of N bodies at AT of BUFFER unless every position, velocity, spin and
orientation number is finite and within its bound (a coordinate below the limit, a speed
component up to MAX-SPEED, a spin below 10^6 rad/s, a quaternion component up to 1.1), each
column tested whole, its words two at a time (snapshot-words-within); a column that fails has
the row it fails at named by refuse-snapshot-body. #SNCHBD"
  (declare (type octets buffer) (type index at n) (type single-float max-speed))
  (let ((coordinate (1- (sb-kernel:single-float-bits (float +physics-coordinate-limit+ 1.0))))
        (speed (sb-kernel:single-float-bits max-speed)) (spin (sb-kernel:single-float-bits 1e6))
        (unit (sb-kernel:single-float-bits 1.1)))
    (dotimes (k 13)
      (let* ((start (+ at (body-part-column n k)))
             (wrong (snapshot-words-within buffer start (+ start (* 4 n))
                                           (cond ((< k 3) coordinate) ((< k 6) speed) ((< k 9) spin) (t unit)))))
        (when wrong
          (refuse-snapshot-body buffer at n (floor (- wrong start) 4) max-speed)
          (snapshot-check nil physics-snapshot-other-layout wrong "a body within its ranges" k))))))

(defun check-snapshot-body-norms (buffer at n max-speed)
  "Refuse the body part of N bodies at AT of BUFFER unless every body's speed is within
MAX-SPEED, its orientation of unit length within a tenth, its time still and its age of 0 or
more and finite, a row at a time, the fault named by refuse-snapshot-body. #SNCHBD"
  (declare (type octets buffer) (type index at n) (type single-float max-speed) #.+kernel-policy+)
  (let ((top (* 1.001 max-speed max-speed)) (still (sb-kernel:single-float-bits 1e30))
        (c3 (+ at (body-part-column n 3))) (c9 (+ at (body-part-column n 9))) (c13 (+ at (body-part-column n 13)))
        (ages (+ at (body-part-column n 14))) (n4 (* 4 n)))
    (declare (type single-float top) (type index c3 c9 c13 ages n4) (type (signed-byte 32) still))
    (sb-sys:with-pinned-objects (buffer)
      (let ((sap (sb-sys:vector-sap buffer)))
        (dotimes (row n)
          (let ((v (sb-sys:sap+ sap (+ c3 (* 4 row)))) (q (sb-sys:sap+ sap (+ c9 (* 4 row)))))
            (macrolet ((at-column (p k) `(sb-sys:sap-ref-single ,p (* ,k n4))))
              (unless (and (<= (+ (* (at-column v 0) (at-column v 0)) (* (at-column v 1) (at-column v 1))
                                  (* (at-column v 2) (at-column v 2)))
                               top)
                           (<= 0.9 (+ (* (at-column q 0) (at-column q 0)) (* (at-column q 1) (at-column q 1))
                                      (* (at-column q 2) (at-column q 2)) (* (at-column q 3) (at-column q 3)))
                               1.1)
                           (let ((b (sb-sys:sap-ref-32 sap (+ c13 (* 4 row))))) (or (<= b still) (= b #x80000000)))
                           (let ((age (sb-sys:sap-ref-64 sap (+ ages (* 8 row)))))
                             (or (<= age #.(sb-kernel:double-float-bits 1d30)) (= age (ash 1 63)))))
                (refuse-snapshot-body buffer at n row max-speed)
                (snapshot-check nil physics-snapshot-other-layout (+ at 4 (* 4 row)) "a body within its ranges" row)))))))))

(defun snapshot-words-within (buffer start end limit)
  "The offset of the first 32-bit word of BUFFER from START below END whose magnitude, its bits
less the sign, exceeds LIMIT's bits, or NIL: two words at a time, each lane's bits raised by
2^31 - 1 - LIMIT, which sets its top bit exactly when it exceeds LIMIT (a NaN's and an
infinity's bits lie above every finite number's). #SNCHBD"
  (declare (type octets buffer) (type index start end) (type (unsigned-byte 31) limit) #.+kernel-policy+)
  (let ((raise (* (- #x7FFFFFFF limit) #x100000001)) (over 0) (i start))
    (declare (type (unsigned-byte 64) raise over) (type index i))
    (sb-sys:with-pinned-objects (buffer)
      (let ((sap (sb-sys:vector-sap buffer)))
        (loop while (<= (+ i 8) end)
              do (setf over (logior over (logand (+ (logand (sb-sys:sap-ref-64 sap i) #x7FFFFFFF7FFFFFFF) raise)
                                                 #xFFFFFFFFFFFFFFFF)))
                 (incf i 8))
        (when (< i end)
          (setf over (logior over (+ (logand (sb-sys:sap-ref-32 sap i) #x7FFFFFFF) (- #x7FFFFFFF limit)))))))
    (unless (zerop (logand over #x8000000080000000))
      (loop for o of-type index from start below end by 4
            unless (<= (logand (snap-u32 buffer o) #x7FFFFFFF) limit) return o))))
;; Checking the bodies on their bits:1 ends here

;; [[file:../physics.org::#SNCHBD][Checking the bodies on their bits:2]]
(defun snapshot-chunk (scratch chunks key)
  "The chunk of the terrain's table CHUNKS under KEY, or NIL, through SCRATCH's cache of the
chunks looked up last, one entry for each of sixteen places of the key's hash. #SNCHBD"
  (declare (type snapshot-scratch scratch) (type hash-table chunks) (type fixnum key) #.+kernel-policy+)
  (let ((keys (snapshot-scratch-chunk-keys scratch)) (place (logand (logxor key (ash key -19) (ash key -38)) 15)))
    (declare (type fixnum-column keys) (type (integer 0 15) place))
    (if (= key (aref keys place))
        (svref (snapshot-scratch-chunks scratch) place)
        (let ((chunk (gethash key chunks)))
          (when chunk
            (setf (aref keys place) key (svref (snapshot-scratch-chunks scratch) place) chunk))
          chunk))))

(defun check-snapshot-bodies (world buffer scratch id marks stamp)
  "Check body part ID of the snapshot in BUFFER: its size, each body's numbers in range
(check-snapshot-body-columns, check-snapshot-body-norms), its slot a slot of the table neither
free nor another body's, marked in MARKS with STAMP + 1, its material one of the palette, and its
centre in no solid cell of WORLD's terrain; return its count. #SNCHBD"
  (declare (type octets buffer) (type snapshot-scratch scratch) (type fixnum-column marks) (type fixnum stamp)
           #.+kernel-policy+)
  (let* ((offsets (snapshot-scratch-offsets scratch)) (at (aref offsets id)) (n (snap-u32 buffer at))
         (count (snap-u32 buffer (aref offsets 2))) (materials (snap-u32 buffer (aref offsets 5)))
         (w (material-index-bytes materials))
         (max-speed (snap-f32 buffer (+ (aref offsets 1) 52 (* 4 (position :max-speed +physics-parameters+ :key #'first)))))
         (terrain (physics-world-terrain world))
         (chunks (and terrain (voxel-terrain-chunks terrain))))
    (declare (type index at n count materials) (type single-float max-speed))
    (check-part-size scratch id (padded (+ 4 (* (body-record-bytes materials) n))))
    (check-snapshot-body-columns buffer at n max-speed)
    (check-snapshot-body-norms buffer at n max-speed)
    ;; the chunks of a terrain that changed since the last restore are looked up again
    (fill (snapshot-scratch-chunk-keys scratch) -1)
    (dotimes (row n n)
      (let ((slot (snap-u32 buffer (+ at (body-part-column n 16) (* 4 row))))
            (material (snap-material-index buffer (+ at (body-part-column n 17) (* w row)) w)))
        (snapshot-check (and (< slot count) (< (aref marks slot) stamp)) physics-snapshot-other-layout
                        (+ at (body-part-column n 16) (* 4 row))
                        "a slot of the table neither free nor another body's" slot)
        (setf (aref marks slot) (1+ stamp))
        (snapshot-check (< material materials) physics-snapshot-other-layout (+ at (body-part-column n 17) (* w row))
                        "a material of the palette" material))
      (when chunks
        (let* ((x (floor (the (single-float -65536.0 65536.0) (snap-f32 buffer (+ at (body-part-column n 0) (* 4 row))))))
               (y (floor (the (single-float -65536.0 65536.0) (snap-f32 buffer (+ at (body-part-column n 1) (* 4 row))))))
               (z (floor (the (single-float -65536.0 65536.0) (snap-f32 buffer (+ at (body-part-column n 2) (* 4 row))))))
               (chunk (snapshot-chunk scratch chunks (chunk-key x y z))))
          (declare (type cell x y z))
          (snapshot-check (and chunk (zerop (aref (the chunk-storage chunk) (cell-offset x y z))))
                          physics-snapshot-other-layout (+ at 4 (* 4 row))
                          "a centre in an air cell of the world's terrain" (list x y z)))))))

(defun check-snapshot-slots (world buffer scratch)
  "Check the handle, material and body parts of the snapshot in BUFFER (check-snapshot-handles,
check-snapshot-materials, check-snapshot-bodies), and that the free slots and the bodies'
slots are every slot of the table. #SNCHBD"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (multiple-value-bind (marks stamp) (check-snapshot-handles buffer scratch)
    (check-snapshot-materials buffer scratch)
    (let* ((hat (aref (snapshot-scratch-offsets scratch) 2)) (count (snap-u32 buffer hat))
           (live (+ (snap-u32 buffer (+ hat 4))
                    (check-snapshot-bodies world buffer scratch 3 marks stamp)
                    (check-snapshot-bodies world buffer scratch 4 marks stamp))))
      (snapshot-check (= live count) physics-snapshot-other-layout hat
                      "as many slots as free slots and bodies" count))))
;; Checking the bodies on their bits:2 ends here

;; [[file:../physics.org::#SNCHCT][Checking the contacts while decoding them:1]]
(defun snapshot-table-room (table n)
  "Give the contact table TABLE room for N keys under contact-table-put's load, emptied, and
return its slots. #SNCHCT"
  (declare (type contact-table table) (type index n))
  (loop while (>= (* 4 (1+ n)) (length (contact-table-slots table)))
        do (let ((size (* 2 (length (contact-table-slots table)))))
             (setf (contact-table-slots table) (make-array size :element-type 'fixnum :initial-element -1)
                   (contact-table-mask table) (1- (ash size -1)))))
  (fill (contact-table-slots table) -1)
  (setf (contact-table-count table) 0)
  (contact-table-slots table))

(defun snapshot-contact-layout (buffer at)
  "Where the parts of the contact part at AT of BUFFER begin: its keys, its flags, then each of
its five streams, and where it ends, as six values after the keys and the flags. #SNCHCT"
  (declare (type octets buffer) (type index at))
  (let* ((n (snap-u32 buffer at)) (keys (+ at +snapshot-contact-head-bytes+)) (flags (+ keys (* 8 n)))
         (s0 (+ flags (* 2 n))) (s1 (+ s0 (* 12 (1+ (snap-u32 buffer (+ at 4))))))
         (s2 (+ s1 (* 4 (1+ (snap-u32 buffer (+ at 8)))))) (s3 (+ s2 (* 8 (1+ (snap-u32 buffer (+ at 12))))))
         (s4 (+ s3 (* 12 (1+ (snap-u32 buffer (+ at 16)))))) (end (+ s4 (* 4 (1+ (snap-u32 buffer (+ at 20)))))))
    (values keys flags s0 s1 s2 s3 s4 end)))

(defun check-snapshot-contact-streams (buffer scratch)
  "Check the frame and the streams of the contact part of the snapshot in BUFFER: no stream
longer than the contacts, its size as the counts give it, every normal written out of unit
length at most, every carried impulse finite and of at most 10^9 N s, and each stream closed by
an entry of zeros. #SNCHCT"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (let* ((at (aref (snapshot-scratch-offsets scratch) 6)) (n (snap-u32 buffer at)))
    (declare (type index at))
    (dotimes (k 5)
      (snapshot-check (<= (snap-u32 buffer (+ at 4 (* 4 k))) n) physics-snapshot-other-layout (+ at 4 (* 4 k))
                      "a stream of no more entries than contacts" (snap-u32 buffer (+ at 4 (* 4 k)))))
    (multiple-value-bind (keys flags s0 s1 s2 s3 s4 end) (snapshot-contact-layout buffer at)
      (declare (ignore keys flags))
      (check-part-size scratch 6 (padded (- end at)))
      (let ((normal (snapshot-words-within buffer s0 s1 (sb-kernel:single-float-bits 1.001)))
            (impulse (snapshot-words-within buffer s1 end (sb-kernel:single-float-bits 1e9))))
        (snapshot-check (null normal) physics-snapshot-other-layout normal "a normal of unit length"
                        (and normal (snap-f32 buffer normal)))
        (snapshot-check (null impulse) physics-snapshot-other-layout impulse "a carried impulse of at most 10^9 N s"
                        (and impulse (snap-f32 buffer impulse))))
      ;; the closing entry of each stream, zeros
      (flet ((closed (start width)
               (loop for o of-type index from (- start (* 4 width)) below start by 4
                     do (snapshot-check (zerop (snap-u32 buffer o)) physics-snapshot-other-layout o
                                        "a stream's closing entry of zeros" (snap-u32 buffer o)))))
        (closed s1 3) (closed s2 1) (closed s3 2) (closed s4 3) (closed end 1)))))

(defun snapshot-contact-rows (world scratch n)
  "SCRATCH's contact rows, laid out as WORLD's contacts, with room for N rows, every row past N
zero again, and its length as many rows as may hold words. #SNCHCT"
  (declare (type snapshot-scratch scratch) (type index n))
  (let ((rows (or (snapshot-scratch-contact-rows scratch)
                  (setf (snapshot-scratch-contact-rows scratch)
                        (make-contact-columns :spare (contact-columns-spare (physics-world-contacts world)))))))
    (contact-columns-ensure-capacity rows n)
    (loop for row of-type index from n below (min (+ (contact-columns-length rows) (contact-columns-spare rows))
                                                 (length (contact-columns-key rows)))
          do (contact-columns-zero-row rows row))
    (setf (contact-columns-length rows) (max n (contact-columns-length rows)))
    rows))
;; Checking the contacts while decoding them:1 ends here

;; [[file:../physics.org::#SNCHCT][Checking the contacts while decoding them:2]]
(declaim (inline check-snapshot-contact-key))
(defun check-snapshot-contact-key (buffer o key count marks stamp)
  "Refuse the contact key word at O of BUFFER, whose key is KEY, unless it is a fixnum's word of
a contact kind and slots of the table (COUNT slots, marked in MARKS as free, STAMP - 1, or
live, STAMP), live or freed in the last step, A below B for a pair. #SNCHCT"
  (declare (type octets buffer) (type index o count) (type fixnum key stamp) (type fixnum-column marks)
           #.+kernel-policy+)
  (let ((kind (ldb (byte 4 58) key)) (a (ldb (byte 24 34) key)))
    ;; a body that expired in the last step has a free slot, and its contacts wait for the next
    ;; step's prune: a key may name a free slot of the table
    (snapshot-check (and (not (logtest (snap-u64 buffer o) 1)) (>= key 0) (< key (ash 1 60)) (<= kind 2)
                         (< a count) (>= (aref marks a) (1- stamp)))
                    physics-snapshot-other-layout o "a contact key of a slot of the table, twice over" (snap-u64 buffer o))
    (when (= kind +contact-pair+)
      (let ((b (ldb (byte 34 0) key)))
        (snapshot-check (and (< a b count) (>= (aref marks b) (1- stamp))) physics-snapshot-other-layout o
                        "a pair key of two slots of the table, the lower first" key)))))

(declaim (inline snapshot-key-put))
(defun snapshot-key-put (slots mask key row)
  "Put KEY, mapped to ROW, into the contact table's SLOTS (MASK + 1 entries) and return true,
or return NIL when KEY is there already. #SNCHCT"
  (declare (type fixnum-column slots) (type fixnum mask key row) #.+kernel-policy+)
  (loop for i of-type fixnum = (contact-slot-hash key mask) then (logand (1+ i) mask)
        for e of-type fixnum = (aref slots (* 2 i))
        do (cond ((= e key) (return nil))
                 ((= e -1) (setf (aref slots (* 2 i)) key (aref slots (1+ (* 2 i))) row) (return t)))))
;; Checking the contacts while decoding them:2 ends here

;; [[file:../physics.org::#SNCHCT][Checking the contacts while decoding them:3]]
(defun decode-snapshot-contacts (buffer scratch rows)
  "Check the keys and flags of the contact part of the snapshot in BUFFER, each key once (into
SCRATCH's contact table, mapped to its row), and write each contact into its row of ROWS: key,
kind, the handles of its slots, seen, order, touching, its normal (written out, or the axis
its code names) and its carried impulses, every other float zero. Run after
check-snapshot-contact-streams and check-snapshot-slots, whose marks it reads. #SNCHCT"
  (declare (type octets buffer) (type snapshot-scratch scratch) (type contact-columns rows) #.+kernel-policy+)
  (let* ((offsets (snapshot-scratch-offsets scratch)) (at (aref offsets 6)) (n (snap-u32 buffer at))
         (hat (aref offsets 2)) (count (snap-u32 buffer hat)) (wat (aref offsets 1))
         (tag (snap-u32 buffer wat)) (step (snap-u64 buffer (+ wat 16)))
         (marks (snapshot-scratch-marks scratch)) (stamp (snapshot-scratch-stamp scratch))
         (table (snapshot-scratch-contacts scratch)) (slots (snapshot-table-room table n))
         (mask (contact-table-mask table)))
    (declare (type index at n hat count wat step) (type (unsigned-byte 16) tag)
             (type fixnum-column marks slots) (type fixnum stamp mask))
    (multiple-value-bind (keys flags s0 s1 s2 s3 s4 end) (snapshot-contact-layout buffer at)
      (declare (type index keys flags s0 s1 s2 s3 s4 end))
      (with-contact-columns (handle-a handle-b kind key seen order touching geometry) rows
        (flet ((slot-handle (slot)
                 ;; the handle of SLOT's body; of a free slot, the handle its body had before it
                 ;; expired, one generation back
                 (declare (type (unsigned-byte 24) slot))
                 (let ((g (snap-u32 buffer (+ hat 8 (* 4 slot)))))
                   (declare (type (unsigned-byte 20) g))
                   (logior (ash tag (+ +handle-index-bits+ +handle-generation-bits+))
                           (ash (if (= (aref marks slot) (1- stamp)) (ldb (byte +handle-generation-bits+ 0) (1- g)) g)
                                +handle-index-bits+)
                           slot))))
          (declare (inline slot-handle))
          (sb-sys:with-pinned-objects (geometry buffer)
            ;; pointers that move on, and each stream's last entry, its closing zeros
            (let* ((base (sb-sys:vector-sap buffer)) (g (sb-sys:vector-sap geometry))
                   (r0 (sb-sys:sap+ base s0)) (r1 (sb-sys:sap+ base s1)) (r2 (sb-sys:sap+ base s2))
                   (r3 (sb-sys:sap+ base s3)) (r4 (sb-sys:sap+ base s4))
                   (z0 (sb-sys:sap+ base (- s1 12))) (z1 (sb-sys:sap+ base (- s2 4))) (z2 (sb-sys:sap+ base (- s3 8)))
                   (z3 (sb-sys:sap+ base (- s4 12))) (z4 (sb-sys:sap+ base (- end 4))))
              (macrolet ((take (r z width first bit)
                           ;; a stream's next entry when the flag BIT is set, else its closing zeros;
                           ;; never past them
                           `(let ((from (if (and (logbitp ,bit f) (sb-sys:sap< ,r ,z)) ,r ,z)))
                              ,@(loop for k below width
                                      collect `(setf (sb-sys:sap-ref-32 g ,(* 4 (+ first k))) (sb-sys:sap-ref-32 from ,(* 4 k))))
                              (setf ,r (sb-sys:sap+ ,r (* ,(* 4 width) (ldb (byte 1 ,bit) f)))))))
                (dotimes (row n)
                  (let* ((o (+ keys (* 8 row))) (k (ash (sb-sys:signed-sap-ref-64 base o) -1))
                         (f (sb-sys:sap-ref-16 base (+ flags (* 2 row)))) (code (ldb (byte 3 2) f)))
                    (declare (type fixnum k) (type (unsigned-byte 16) f))
                    (check-snapshot-contact-key buffer o k count marks stamp)
                    (snapshot-check (and (< f 512) (/= 7 code)) physics-snapshot-other-layout (+ flags (* 2 row))
                                    "contact flags of 9 bits, a normal code from 0 to 6" f)
                    ;; a key already in the table is a duplicate
                    (snapshot-check (snapshot-key-put slots mask k row) physics-snapshot-other-layout o
                                    "a key no other contact has" k)
                    (setf (aref key row) k (aref kind row) (ldb (byte 4 58) k)
                          (aref handle-a row) (slot-handle (ldb (byte 24 34) k))
                          (aref handle-b row) (if (= (ldb (byte 4 58) k) +contact-pair+) (slot-handle (ldb (byte 24 0) k)) +no-body+)
                          (aref seen row) (if (logbitp 1 f) (1- step) step)
                          (aref order row) row
                          (aref touching row) (ldb (byte 1 0) f))
                    ;; the normal: written out, or the unit axis its code names
                    (if (zerop code)
                        (let ((from (if (sb-sys:sap< r0 z0) r0 z0)))
                          (setf (sb-sys:sap-ref-32 g 0) (sb-sys:sap-ref-32 from 0) (sb-sys:sap-ref-32 g 4) (sb-sys:sap-ref-32 from 4)
                                (sb-sys:sap-ref-32 g 8) (sb-sys:sap-ref-32 from 8)
                                r0 (sb-sys:sap+ r0 12)))
                        (setf (sb-sys:sap-ref-32 g 0) 0 (sb-sys:sap-ref-32 g 4) 0 (sb-sys:sap-ref-32 g 8) 0
                              (sb-sys:sap-ref-32 g (* 4 (ash (1- code) -1))) (if (oddp code) #x3F800000 #xBF800000)))
                    (setf (sb-sys:sap-ref-32 g 12) 0 (sb-sys:sap-ref-32 g 16) 0 (sb-sys:sap-ref-32 g 20) 0
                          (sb-sys:sap-ref-32 g 24) 0 (sb-sys:sap-ref-32 g 28) 0 (sb-sys:sap-ref-32 g 32) 0
                          (sb-sys:sap-ref-32 g 36) 0)
                    (take r1 z1 1 #.(position 'normal-impulse +contact-fields+) 5)
                    (take r2 z2 2 #.(position 'tangent-impulse-1 +contact-fields+) 6)
                    (take r3 z3 3 #.(position 'rolling-impulse-x +contact-fields+) 7)
                    (take r4 z4 1 #.(position 'spin-impulse +contact-fields+) 8)
                    (setf g (sb-sys:sap+ g #.(* 4 (length +contact-fields+))))))
                ;; every stream read to its end, no further
                (snapshot-check (and (sb-sys:sap= r0 z0) (sb-sys:sap= r1 z1) (sb-sys:sap= r2 z2) (sb-sys:sap= r3 z3)
                                     (sb-sys:sap= r4 z4))
                                physics-snapshot-other-layout flags
                                "as many contacts flagged for each stream as its count" n)))))))
    (setf (contact-table-count table) n (contact-columns-length rows) n)
    table))

(defun check-snapshot-contacts (world buffer scratch)
  "Check the contact part of the snapshot in BUFFER, stage by stage: its frame and streams, then
each contact's key and flags as it is decoded into SCRATCH's rows, laid out as WORLD's contacts,
for the restore to trade for the world's. #SNCHCT"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (check-snapshot-contact-streams buffer scratch)
  (decode-snapshot-contacts buffer scratch
                            (snapshot-contact-rows world scratch (snap-u32 buffer (aref (snapshot-scratch-offsets scratch) 6)))))
;; Checking the contacts while decoding them:3 ends here

;; [[file:../physics.org::#SNCHCT][Checking the contacts while decoding them:4]]
(defun check-snapshot-pair-list (buffer scratch)
  "Check the pair list part of the snapshot in BUFFER: its form and the size its counts give,
its numbers, finite anchors within the coordinate limit, no more rows than awake bodies when
their handles are not written, and pairs of listed rows, written whole or as differences, each
pair left in SCRATCH's pairs as the list holds it. #SNCHCT"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((offsets (snapshot-scratch-offsets scratch))
         (at (aref offsets 7)) (rows (snap-i32 buffer at)) (pairs (snap-u32 buffer (+ at 32)))
         (form (snap-u32 buffer (+ at 36))) (n (max rows 0))
         (coordinate (sb-kernel:single-float-bits (float +physics-coordinate-limit+ 1.0))))
    (declare (type index at) (type fixnum rows n) (type (unsigned-byte 32) pairs form)
             (type (signed-byte 32) coordinate))
    (snapshot-check (< -2 rows (ash 1 24)) physics-snapshot-other-layout at "a count of listed rows" rows)
    (snapshot-check (or (>= rows 0) (zerop pairs)) physics-snapshot-other-layout (+ at 32) "no pairs in no list" pairs)
    (snapshot-check (< form 4) physics-snapshot-other-layout (+ at 36) "a form of 2 bits" form)
    (let* ((clear (+ at +snapshot-pair-head-bytes+ (* +snapshot-pair-row-bytes+ n)))
           (handles (+ clear (* 4 (ceiling n 32))))
           (list (+ handles (if (logbitp 0 form) (* 8 n) 0))))
      (declare (type index clear handles list))
      (let* ((whole (padded (+ list (* 3 pairs))))
             (wholes (if (and (logbitp 1 form) (<= (+ whole 4) (length buffer))) (snap-u32 buffer whole) 0)))
        (check-part-size scratch 7 (- (if (logbitp 1 form) (+ whole 4 (* 4 wholes)) (+ list (* 8 pairs))) at)))
      (when (>= rows 0)
        (let ((cell (snap-finite-f32 buffer (+ at 4))))
          (snapshot-check (< 0.0 cell 1e6) physics-snapshot-other-layout (+ at 4) "a cell edge above 0" cell))
        (snapshot-check (<= -1 (snap-i32 buffer (+ at 12)) rows) physics-snapshot-other-layout (+ at 12)
                        "a count of loose rows" (snap-i32 buffer (+ at 12)))
        (dolist (o '(16 24))
          (snapshot-check (typep (snap-i64 buffer (+ at o)) 'fixnum) physics-snapshot-other-layout (+ at o)
                          "a step number" (snap-i64 buffer (+ at o))))
        (loop for o of-type index from (+ at +snapshot-pair-head-bytes+) below clear by 4
              do (unless (< (logand (snap-u32 buffer o) #x7FFFFFFF) coordinate)
                   (snapshot-check nil physics-snapshot-other-layout o "a finite anchor within the coordinate limit"
                                   (snap-u32 buffer o))))
        (if (logbitp 0 form)
            (dotimes (i n)
              (snapshot-check (typep (snap-i64 buffer (+ handles (* 8 i))) 'fixnum) physics-snapshot-other-layout
                              (+ handles (* 8 i)) "a handle" (snap-i64 buffer (+ handles (* 8 i)))))
            (snapshot-check (<= n (snap-u32 buffer (aref offsets 3))) physics-snapshot-other-layout at
                            "no more listed rows than awake bodies, whose handles the rows had" rows))
        (let ((out (setf (snapshot-scratch-pairs scratch)
                         (fixnum-room (snapshot-scratch-pairs scratch) pairs :keep 0 :least 1024))))
          (declare (type fixnum-column out))
          (if (logbitp 1 form)
              ;; the rows the differences give, each a listed row, each pair kept as the list holds it
              (let* ((a 0) (whole (padded (+ list (* 3 pairs)))) (wholes (snap-u32 buffer whole)) (taken 0))
                (declare (type fixnum a) (type index whole wholes taken))
                (dotimes (k pairs)
                  (let* ((da (snap-u8 buffer (+ list k))) (db (snap-u16 buffer (+ list pairs (* 2 k))))
                         (b 0))
                    (declare (type fixnum b))
                    (if (= da 128)
                        (progn (snapshot-check (< taken wholes) physics-snapshot-other-layout (+ list k)
                                               "a row listed whole for each pair that needs one" taken)
                               (setf a (snap-u32 buffer (+ whole 4 (* 4 taken))))
                               (incf taken))
                        (incf a (if (> da 128) (- da 256) da)))
                    (setf b (+ a (if (>= db 32768) (- db 65536) db)))
                    (snapshot-check (and (<= 0 a) (< a n) (<= 0 b) (< b n)) physics-snapshot-other-layout (+ list k)
                                    "a pair of listed rows" (list a b))
                    (setf (aref out k) (logior (ash a 24) b))))
                (snapshot-check (= taken wholes) physics-snapshot-other-layout whole
                                "as many rows listed whole as pairs that need one" wholes))
              (dotimes (k pairs)
                (let ((p (snap-i64 buffer (+ list (* 8 k)))))
                  (snapshot-check (and (>= p 0) (< (ash p -24) n) (< (ldb (byte 24 0) p) n))
                                  physics-snapshot-other-layout (+ list (* 8 k)) "a pair of listed rows" p)
                  (setf (aref out k) p)))))))))
;; Checking the contacts while decoding them:4 ends here

;; [[file:../physics.org::#SNCHCT][Checking the contacts while decoding them:5]]
(defun check-snapshot-rest (buffer scratch)
  "Check the box and push parts of the snapshot in BUFFER: sizes, finite numbers, and pushes that
cover the table with nothing on a free slot. #SNCHCT"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((at (aref (snapshot-scratch-offsets scratch) 8)) (n (snap-u32 buffer at)))
    (declare (type index at))
    (check-part-size scratch 8 (+ 4 (* +snapshot-box-bytes+ n)))
    (dotimes (row n)
      (let ((o (+ at 4 (* row +snapshot-box-bytes+))))
        (dotimes (k 9)
          (let ((c (snap-finite-f32 buffer (+ o (* 4 k)))))
            (snapshot-check (< (abs c) +physics-coordinate-limit+) physics-snapshot-other-layout (+ o (* 4 k))
                            "a box's number within the coordinate limit" c)))
        (dotimes (k 3)
          (snapshot-check (<= (snap-f32 buffer (+ o (* 4 k))) (snap-f32 buffer (+ o 12 (* 4 k))))
                          physics-snapshot-other-layout (+ o (* 4 k)) "a box's low corner below its high" k))
        (snapshot-check (<= 0 (snap-i64 buffer (+ o 36)) (ash 1 34)) physics-snapshot-other-layout (+ o 36)
                        "a box id" (snap-i64 buffer (+ o 36)))
        (snapshot-check (<= 0 (snap-i64 buffer (+ o 44)) #xFFFFFFFF) physics-snapshot-other-layout (+ o 44)
                        "a box filter of 32 bits" (snap-i64 buffer (+ o 44))))))
  (let* ((offsets (snapshot-scratch-offsets scratch))
         (at (aref offsets 9)) (slots (snap-u32 buffer at))
         (hat (aref offsets 2)) (count (snap-u32 buffer hat))
         (pushed (logbitp 3 (snap-u32 buffer (+ (aref offsets 1) 8))))
         (marks (snapshot-scratch-marks scratch)) (live (snapshot-scratch-stamp scratch)))
    (declare (type index at hat) (type fixnum-column marks))
    (snapshot-check (or (zerop slots) (= slots count)) physics-snapshot-other-layout at
                    "pushes for no slot or for every slot of the table" slots)
    (check-part-size scratch 9 (+ 4 (* 16 slots)))
    (dotimes (slot slots)
      (let ((o (+ at 4 (* 16 slot))))
        (dotimes (k 3)
          (snapshot-check (<= (abs (snap-finite-f32 buffer (+ o (* 4 k)))) (* +physics-max-acceleration+ +physics-max-mass+))
                          physics-snapshot-other-layout (+ o (* 4 k)) "a force in range" (snap-f32 buffer (+ o (* 4 k)))))
        (snap-finite-f32 buffer (+ o 12))
        (snapshot-check (<= (abs (snap-f32 buffer (+ o 12))) +physics-max-gravity-scale+)
                        physics-snapshot-other-layout (+ o 12) "a gravity scale in range" (snap-f32 buffer (+ o 12)))
        (let ((forced (or (/= 0.0 (snap-f32 buffer o)) (/= 0.0 (snap-f32 buffer (+ o 4))) (/= 0.0 (snap-f32 buffer (+ o 8))))))
          (snapshot-check (or (= (aref marks slot) live) (and (not forced) (= 1.0 (snap-f32 buffer (+ o 12)))))
                          physics-snapshot-other-layout o "no force and a gravity scale of 1 on a free slot" slot)
          (snapshot-check (or pushed (not forced)) physics-snapshot-other-layout o
                          "no force unless one was applied" slot))))))
;; Checking the contacts while decoding them:5 ends here

;; [[file:../physics.org::#SNPUTB][Putting a world back:1]]
;;; applying a checked snapshot: nothing here can fail

(defun apply-snapshot-bodies (world bodies set buffer at mat)
  "Fill BODIES, WORLD's set SET, from the checked body part at AT of BUFFER, the float columns and
the ages copied whole, its materials from the palette at MAT, and point each body's handle slot
at its row; rows it held past the new count read as zeros again. #SNPUTB"
  (declare (type body-columns bodies) (type octets buffer) (type index at mat) (type fixnum set)
           #.+kernel-policy+)
  (let* ((n (snap-u32 buffer at)) (old (body-columns-length bodies)) (ids (physics-world-ids world))
         (w (material-index-bytes (snap-u32 buffer mat)))
         (tag (handle-table-tag ids))
         (sets (handle-table-set ids)) (locals (handle-table-local ids)) (generations (handle-table-generation ids)))
    (declare (type index n old) (type (unsigned-byte 16) tag) (type fixnum-column sets locals generations))
    (body-columns-ensure-capacity bodies n)
    (setf (body-columns-length bodies) n)
    ;; the rows past N that held bodies, and the spare rows, read as zeros
    (loop for row of-type index from n below (min (+ (max old n) (body-columns-spare bodies)) (length (body-columns-x bodies)))
          do (body-columns-zero-row bodies row))
    (do-snapshot-body-floats (column k) bodies
      (sb-kernel:%byte-blt buffer (+ at (body-part-column n k)) column 0 (* 4 n)))
    (sb-kernel:%byte-blt buffer (+ at (body-part-column n 14)) (body-columns-age bodies) 0 (* 8 n))
    (with-body-columns (flags handle radius inverse-mass inverse-inertia restitution friction rolling-resistance life kind)
        bodies
      (let ((s (+ at (body-part-column n 16))) (m (+ at (body-part-column n 17))) (f (+ at (body-part-column n 18 w))))
        (declare (type index s m f))
        (dotimes (row n)
          (let* ((slot (snap-u32 buffer (+ s (* 4 row))))
                 (p (+ mat 4 (* (snap-material-index buffer (+ m (* w row)) w) +snapshot-material-bytes+)))
                 (generation (aref generations slot)))
            (declare (type index p) (type (unsigned-byte 24) slot) (type (unsigned-byte 20) generation))
            (setf (aref radius row) (snap-f32 buffer p) (aref inverse-mass row) (snap-f32 buffer (+ p 4))
                  (aref inverse-inertia row) (snap-f32 buffer (+ p 8)) (aref restitution row) (snap-f32 buffer (+ p 12))
                  (aref friction row) (snap-f32 buffer (+ p 16)) (aref rolling-resistance row) (snap-f32 buffer (+ p 20))
                  (aref life row) (snap-f32 buffer (+ p 24)) (aref kind row) (snap-i32 buffer (+ p 28))
                  (aref flags row) (logior (snap-u16 buffer (+ f (* 2 row))) (ash (snap-u32 buffer (+ p 32)) 16))
                  (aref handle row) (logior (ash tag (+ +handle-index-bits+ +handle-generation-bits+))
                                            (ash generation +handle-index-bits+) slot)
                  (aref sets slot) set (aref locals slot) row)))))))

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter +snapshot-traded-contact-columns+ '(handle-a handle-b kind key seen order touching geometry)
    "The columns of a contact that a restore decodes and trades for the world's: every column of
contact-columns. #SNPUTB"))

(defun apply-snapshot-contacts (world buffer scratch)
  "Give WORLD the contacts the check decoded into SCRATCH's rows, by trading their columns for the
world's, and the table of their keys the check filled, traded the same way. #SNPUTB"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((wat (aref (snapshot-scratch-offsets scratch) 1)) (step (snap-u64 buffer (+ wat 16)))
         (contacts (physics-world-contacts world)) (rows (snapshot-scratch-contact-rows scratch))
         (table (physics-world-contact-table world)) (full (snapshot-scratch-contacts scratch)))
    (declare (type index wat step) (type contact-columns contacts rows))
    (macrolet ((trade ()
                 `(progn ,@(loop for c in (append +snapshot-traded-contact-columns+ '(length capacity))
                                 for reader = (intern (format nil "CONTACT-COLUMNS-~A" c) (symbol-package 'contact-columns))
                                 collect `(rotatef (,reader contacts) (,reader rows))))))
      (trade))
    (contact-columns-ensure-capacity (physics-world-contact-scratch world) (contact-columns-capacity contacts))
    ;; the table the check filled becomes the world's, and the world's the scratch's
    (rotatef (contact-table-slots table) (contact-table-slots full))
    (rotatef (contact-table-mask table) (contact-table-mask full))
    (rotatef (contact-table-count table) (contact-table-count full))
    (setf (contact-table-step table) step (contact-table-cursor table) 0 (contact-table-touched table) 0
          (contact-table-misses table) (snap-u64 buffer (+ wat 140)))))
;; Putting a world back:1 ends here

;; [[file:../physics.org::#SNPUTB][Putting a world back:2]]
(defun snapshot-holds-grid-p (world buffer at grid-step)
  "True when WORLD's awake grid, of step GRID-STEP, is already the one the pair list part at AT of
the snapshot BUFFER would have bucketed: the world's grid is its pair list's build, and that
build is the snapshot's, of as many rows, the same cell, the same count of builds and the same
anchors to the bit. #SNPUTB"
  (declare (type octets buffer) (type index at) (type fixnum grid-step))
  (let* ((plist (physics-world-pair-list world)) (rows (snap-i32 buffer at)) (anchors (pair-list-anchors plist)))
    (declare (type fixnum rows) (type f32-column anchors))
    (and (>= rows 0) (= rows (pair-list-rows plist))
         (= grid-step (pair-list-built-step plist) (snap-i64 buffer (+ at 24)))
         (= (pair-list-builds plist) (snap-u32 buffer (+ at 8)))
         (= (sb-kernel:single-float-bits (pair-list-cell plist)) (snap-i32 buffer (+ at 4)))
         (<= (* 3 rows) (length anchors))
         (sb-sys:with-pinned-objects (anchors)
           (let ((sap (sb-sys:vector-sap anchors)) (from (+ at +snapshot-pair-head-bytes+)))
             (loop for o of-type index from 0 below (* 12 rows) by 4
                   always (= (sb-sys:sap-ref-32 sap o) (snap-u32 buffer (+ from o)))))))))

(defun apply-snapshot-pair-list (world buffer scratch grid-step)
  "Put the pair list of the checked snapshot BUFFER into WORLD, the rows' handles the awake rows'
own when the snapshot does not write them (the bodies are restored first), and the awake grid of
its build when the snapshot's grid still is that build's, bucketed again unless WORLD's grid, of
step GRID-STEP, is that grid already (snapshot-holds-grid-p); the pairs are those the check
decoded into SCRATCH, traded for the list's. #SNPUTB"
  (declare (type octets buffer) (type snapshot-scratch scratch) (type fixnum grid-step) #.+kernel-policy+)
  (let* ((at (aref (snapshot-scratch-offsets scratch) 7)) (rows (snap-i32 buffer at)) (pairs (snap-u32 buffer (+ at 32)))
         (form (snap-u32 buffer (+ at 36))) (plist (physics-world-pair-list world))
         ;; read before the list is overwritten
         (kept (snapshot-holds-grid-p world buffer at grid-step)))
    (declare (type index at pairs) (type fixnum rows))
    (setf (pair-list-rows plist) rows (pair-list-terrain plist) nil (pair-list-terrain-edits plist) -1
          (pair-list-count plist) 0)
    (when (>= rows 0)
      (pair-list-room plist rows)
      (let* ((handles (pair-list-handles plist)) (clear (pair-list-clear plist))
             (bits (+ at +snapshot-pair-head-bytes+ (* +snapshot-pair-row-bytes+ rows)))
             (o (+ bits (* 4 (ceiling rows 32)))))
        (declare (type fixnum-column handles clear) (type index bits o))
        (fill (pair-list-loose plist) 0)
        (sb-kernel:%byte-blt buffer (+ at +snapshot-pair-head-bytes+) (pair-list-anchors plist) 0 (* 12 rows))
        (dotimes (i rows)
          (setf (aref clear i) (ldb (byte 1 (logand i 31)) (snap-u32 buffer (+ bits (* 4 (ash i -5)))))))
        (if (logbitp 0 form)
            (dotimes (i rows) (setf (aref handles i) (snap-i64 buffer o)) (incf o 8))
            (replace handles (body-columns-handle (physics-world-awake world)) :end1 rows))
        ;; the pairs the check decoded
        (rotatef (pair-list-pairs plist) (snapshot-scratch-pairs scratch)))
      (setf (pair-list-count plist) pairs (pair-list-cell plist) (snap-f32 buffer (+ at 4))
            (pair-list-builds plist) (snap-u32 buffer (+ at 8)) (pair-list-loose-count plist) (snap-i32 buffer (+ at 12))
            (pair-list-step plist) (snap-i64 buffer (+ at 16)) (pair-list-built-step plist) (snap-i64 buffer (+ at 24)))
      (when (and (= (physics-world-awake-grid-step world) (pair-list-built-step plist)) (not kept))
        ;; the grid of the list's build, bucketed again from the anchors it was built from
        (let ((xs (pair-list-loose-x plist)) (ys (pair-list-loose-y plist)) (zs (pair-list-loose-z plist))
              (anchors (pair-list-anchors plist)))
          (dotimes (i rows)
            (setf (aref xs i) (aref anchors (* 3 i)) (aref ys i) (aref anchors (+ 1 (* 3 i)))
                  (aref zs i) (aref anchors (+ 2 (* 3 i)))))
          (build-hash-grid (physics-world-awake-grid world) (pair-list-cell plist) rows xs ys zs
                           (awake-row-identities world rows)))))))
;; Putting a world back:2 ends here

;; [[file:../physics.org::#SNPUTB][Putting a world back:3]]
(defun apply-snapshot (world buffer scratch)
  "Put WORLD into the state of the checked snapshot BUFFER, whose parts SCRATCH located and whose
contact keys SCRATCH's contact table holds. #SNPUTB"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((offsets (snapshot-scratch-offsets scratch))
         (wat (aref offsets 1)) (hat (aref offsets 2))
         (ids (physics-world-ids world))
         (count (snap-u32 buffer hat)) (nfree (snap-u32 buffer (+ hat 4)))
         (step (snap-u64 buffer (+ wat 16)))
         (flags (snap-u32 buffer (+ wat 8))) (grid-step (physics-world-awake-grid-step world)))
    (declare (type index wat hat count nfree step) (type fixnum grid-step))
    ;; the world part: its numbers, parameters and the last step's statistics
    (setf (handle-table-tag ids) (snap-u32 buffer wat)
          (physics-world-filtering world) (logbitp 1 flags)
          (physics-world-column-watch world) (logbitp 2 flags)
          (physics-world-substeps world) (snap-u32 buffer (+ wat 12))
          (physics-world-step-count world) step
          (physics-world-step-seconds world) (snap-f32 buffer (+ wat 24))
          (physics-world-gravity-x world) (snap-f32 buffer (+ wat 28))
          (physics-world-gravity-y world) (snap-f32 buffer (+ wat 32))
          (physics-world-gravity-z world) (snap-f32 buffer (+ wat 36))
          (physics-world-current-dt world) (snap-f32 buffer (+ wat 40))
          (physics-world-current-h world) (snap-f32 buffer (+ wat 44))
          (physics-world-max-radius world) (snap-f32 buffer (+ wat 48)))
    (loop for (name nil nil nil kind) in +physics-parameters+
          for o of-type index from (+ wat 52) by 4
          do (setf (world-parameter world name) (if (eq kind 'integer) (snap-u32 buffer o) (snap-f32 buffer o))))
    (let ((stats (world-statistics world)))
      (setf (physics-world-braced-step world) (snap-i64 buffer (+ wat 124))
            (physics-world-awake-grid-step world) (snap-i64 buffer (+ wat 132))
            (step-statistics-contacts stats) (snap-u32 buffer (+ wat 148))
            (step-statistics-colors stats) (snap-u32 buffer (+ wat 152))
            (step-statistics-real-seconds stats) (snap-f64 buffer (+ wat 156))
            (step-statistics-max-penetration stats) (snap-f64 buffer (+ wat 164))
            (step-statistics-max-approach stats) (snap-f64 buffer (+ wat 172))))
    ;; the handle table: its generations, every slot free, then the free list chained
    (loop while (> count (length (handle-table-set ids)))
          do (let ((n (* 2 (length (handle-table-set ids)))))
               (flet ((grow (a init) (replace (make-array n :element-type 'fixnum :initial-element init) a)))
                 (setf (handle-table-set ids) (grow (handle-table-set ids) +set-free+)
                       (handle-table-local ids) (grow (handle-table-local ids) -1)
                       (handle-table-generation ids) (grow (handle-table-generation ids) 0)))))
    (let ((sets (handle-table-set ids)) (locals (handle-table-local ids)) (generations (handle-table-generation ids)))
      (declare (type fixnum-column sets locals generations))
      (fill sets +set-free+) (fill locals -1)
      (fill generations 0 :start count)
      (dotimes (slot count) (setf (aref generations slot) (snap-u32 buffer (+ hat 8 (* 4 slot)))))
      (setf (handle-table-count ids) count
            (handle-table-free ids) (if (plusp nfree) (snap-u32 buffer (+ hat 8 (* 4 count))) -1))
      (dotimes (k nfree)
        (setf (aref locals (snap-u32 buffer (+ hat 8 (* 4 count) (* 4 k))))
              (if (< (1+ k) nfree) (snap-u32 buffer (+ hat 8 (* 4 count) (* 4 (1+ k)))) -1))))
    ;; the bodies added since the last step
    (let* ((o (+ hat 8 (* 4 count) (* 4 nfree))) (n (snap-u32 buffer o)) (tag (handle-table-tag ids)))
      (declare (type index o n))
      (when (< (length (physics-world-added world)) n)
        (setf (physics-world-added world) (fixnum-room (physics-world-added world) n :least 16)))
      (let ((added (physics-world-added world)))
        (declare (type fixnum-column added))
        (dotimes (k n)
          (setf (aref added k) (make-handle tag (snap-u32 buffer (+ o 8 (* 8 k))) (snap-u32 buffer (+ o 4 (* 8 k)))))))
      (setf (physics-world-added-count world) n))
    ;; the bodies, awake and sleeping, in their rows
    (apply-snapshot-bodies world (physics-world-awake world) +set-awake+ buffer (aref offsets 3) (aref offsets 5))
    (apply-snapshot-bodies world (physics-world-sleeping world) +set-sleeping+ buffer (aref offsets 4) (aref offsets 5))
    (let ((sleeping (physics-world-sleeping world)))
      (setf (physics-world-mortal-sleepers world)
            (let ((life (body-columns-life sleeping)))
              (declare (type f32-column life))
              (loop for row of-type index below (body-columns-length sleeping) count (plusp (aref life row))))))
    ;; the contacts in their rows, then the pair list and its grid
    (apply-snapshot-contacts world buffer scratch)
    (apply-snapshot-pair-list world buffer scratch grid-step)
    ;; the sleeping grids are built again from every sleeper at the next step
    (let ((of (sleeping-grid-of world)))
      (fill of 0)
      (setf (hash-grid-inv-cell (physics-world-sleeping-grid world)) 0.0
            (physics-world-fresh-count world) 0 (physics-world-newest-count world) 0
            (physics-world-settled-count world) 0 (physics-world-settled-stale world) 0
            (physics-world-sleeping-grid-dirty world) t))
    ;; the posted boxes, without their owners
    (let* ((at (aref offsets 8)) (n (snap-u32 buffer at)) (boxes (physics-world-boxes world)))
      (declare (type index at n))
      (box-columns-clear boxes)
      (fill (physics-world-box-owners world) nil)
      (dotimes (k n)
        (let ((row (box-columns-append boxes)) (o (+ at 4 (* k +snapshot-box-bytes+))))
          (with-box-columns (min-x min-y min-z max-x max-y max-z vx vy vz (bid id) filter) boxes
            (setf (aref min-x row) (snap-f32 buffer o) (aref min-y row) (snap-f32 buffer (+ o 4))
                  (aref min-z row) (snap-f32 buffer (+ o 8)) (aref max-x row) (snap-f32 buffer (+ o 12))
                  (aref max-y row) (snap-f32 buffer (+ o 16)) (aref max-z row) (snap-f32 buffer (+ o 20))
                  (aref vx row) (snap-f32 buffer (+ o 24)) (aref vy row) (snap-f32 buffer (+ o 28))
                  (aref vz row) (snap-f32 buffer (+ o 32)) (aref bid row) (snap-i64 buffer (+ o 36))
                  (aref filter row) (snap-i64 buffer (+ o 44)))))))
    (when (> (box-columns-length (physics-world-boxes world)) (length (physics-world-box-owners world)))
      (setf (physics-world-box-owners world)
            (make-array (* 2 (box-columns-length (physics-world-boxes world))) :initial-element nil)))
    ;; the forces and gravity scales by slot
    (let* ((at (aref offsets 9)) (slots (snap-u32 buffer at)))
      (declare (type index at slots))
      (if (zerop slots)
          (setf (physics-world-pushes world) nil (physics-world-scaled-count world) 0
                (physics-world-pushed world) nil)
          (let ((pushes (ensure-pushes world)) (scaled 0))
            (declare (type f32-column pushes) (type index scaled))
            (loop for p from 0 below (length pushes) by 4
                  do (setf (aref pushes p) 0.0 (aref pushes (+ p 1)) 0.0 (aref pushes (+ p 2)) 0.0 (aref pushes (+ p 3)) 1.0))
            (dotimes (k (* 4 slots)) (setf (aref pushes k) (snap-f32 buffer (+ at 4 (* 4 k)))))
            (dotimes (slot slots) (when (/= 1.0 (aref pushes (+ 3 (* 4 slot)))) (incf scaled)))
            (setf (physics-world-scaled-count world) scaled (physics-world-pushed world) (logbitp 3 flags)))))
    ;; what a step leaves for the caller to read goes; caches keyed by the step are stale
    (event-columns-clear (physics-world-events world))
    (fill (physics-world-event-data world) nil)
    (setf (physics-world-near-cells-step world) -1 (physics-world-box-touch-step world) -1
          (physics-world-undo-open world) nil)
    (incf (physics-world-rows-version world))
    (apply-snapshot-joints world buffer scratch)
    (apply-snapshot-box-bodies world buffer scratch)
    world))
;; Putting a world back:3 ends here

;; [[file:../physics.org::#SNPUTB][Putting a world back:4]]
(defun restore-physics-world (world buffer)
  "Put WORLD back into the state the snapshot BUFFER (from snapshot-physics-world) holds, and
return WORLD; into a world whose buffers are large enough it conses nothing. A snapshot that is
truncated, of another magic, version or layout, whose checksum fails, or of a world with
features WORLD lacks, signals the physics-snapshot-invalid subtype naming the byte offset, and
WORLD is left as it was. #SNPUTB"
  (check-idle world 'restore-physics-world)
  (unless (typep buffer 'octets)
    (error 'invalid-physics-parameter :world world :name :buffer :value buffer
                                      :expected "an octet vector, (simple-array (unsigned-byte 8) (*))"))
  (let ((scratch (world-snapshot-scratch world)))
    (check-snapshot world buffer scratch)
    (sb-int:with-float-traps-masked (:inexact :underflow) (apply-snapshot world buffer scratch))
    world))
;; Putting a world back:4 ends here

;; [[file:../physics.org::#SNDISK][On disk, and a saved world in the viewer:1]]
;;; on disk: the same bytes, to a stream or a file

(defun write-physics-world (world destination)
  "Write WORLD's snapshot to DESTINATION, a binary output stream of octets or a pathname (a file
made or replaced), and return the bytes written. #SNDISK"
  (check-idle world 'write-physics-world)
  (multiple-value-bind (buffer size) (snapshot-physics-world world)
    (flet ((out (stream) (write-sequence buffer stream :end size)))
      (if (streamp destination)
          (out destination)
          (with-open-file (stream destination :direction :output :element-type '(unsigned-byte 8)
                                              :if-exists :supersede :if-does-not-exist :create)
            (out stream))))
    size))

(defun read-snapshot-octets (source)
  "The octets of the snapshot SOURCE holds, a binary input stream of octets or a pathname: the
header, then as many bytes as it records, or as many as there are. #SNDISK"
  (flet ((in (stream)
           (let* ((header (make-array +snapshot-header-bytes+ :element-type '(unsigned-byte 8)))
                  (got (read-sequence header stream)))
             (if (or (< got +snapshot-header-bytes+) (mismatch header +snapshot-magic+ :end1 8))
                 (subseq header 0 got)
                 (let* ((total (min (snap-u64 header 16) (ash 1 34)))
                        (buffer (make-array (max total +snapshot-header-bytes+) :element-type '(unsigned-byte 8))))
                   (replace buffer header)
                   (let ((end (read-sequence buffer stream :start +snapshot-header-bytes+)))
                     (if (< end (length buffer)) (subseq buffer 0 end) buffer)))))))
    (if (streamp source)
        (in source)
        (with-open-file (stream source :element-type '(unsigned-byte 8)) (in stream)))))

(defun read-physics-world (source &key terrain into (kernels nil))
  "Read the snapshot SOURCE holds (a binary input stream or a pathname, as write-physics-world
wrote it) and return the world it describes: restored INTO that world when given, else into a
new world over TERRAIN (the caller's, as the snapshot holds no cells) made with the snapshot's
step, substeps, gravity, sleep and features, and KERNELS, or the family the snapshot names when
this machine runs it. Bad bytes signal as restore-physics-world does. #SNDISK"
  (let* ((buffer (coerce (read-snapshot-octets source) 'octets))
         (scratch (make-snapshot-scratch)))
    (if into
        (restore-physics-world into buffer)
        (progn
          (check-snapshot-frame buffer scratch)
          (check-part-size scratch 1 +snapshot-world-bytes+)
          (let* ((at (aref (snapshot-scratch-offsets scratch) 1))
                 (mask (snap-u32 buffer (+ at 4)))
                 (name (map 'string #'code-char (remove 0 (subseq buffer (+ at 188) (+ at 204)))))
                 (family (find-symbol name :keyword))
                 (world (make-physics-world
                         :terrain terrain
                         :step-seconds (snap-finite-f32 buffer (+ at 24))
                         :substeps (snap-u32 buffer (+ at 12))
                         :gravity (loop for k below 3 collect (snap-finite-f32 buffer (+ at 28 (* 4 k))))
                         :sleep (logbitp 0 (snap-u32 buffer (+ at 8)))
                         :features (loop for f in +physics-features+ for k from 0 when (logbitp k mask) collect f)
                         :kernels (or kernels
                                      (if (and family (assoc family (runnable-kernel-families))) family :scalar)))))
            (restore-physics-world world buffer))))))
;; On disk, and a saved world in the viewer:1 ends here

;; [[file:../physics.org::#SNJOIN][Joints in a snapshot:1]]
(defun write-snapshot-joints (world buffer at)
  "Write the joints part of WORLD's snapshot into BUFFER from AT: the joint handle table, the
limits' softness and a record per joint. #SNJOIN"
  (declare (type octets buffer) (type index at) #.+kernel-policy+)
  (let* ((set (physics-world-joints world)) (jids (joint-set-ids set)) (count (handle-table-count jids))
         (rows (joint-set-rows set)) (n (joint-columns-length rows))
         (generations (handle-table-generation jids)) (nfree 0))
    (declare (type index count n nfree))
    (setf (snap-u32 buffer at) n (snap-u32 buffer (+ at 4)) count
          (snap-f32 buffer (+ at 12)) (joint-set-limit-bias set) (snap-f32 buffer (+ at 16)) (joint-set-limit-mass set))
    (dotimes (slot count) (setf (snap-u32 buffer (+ at 20 (* 4 slot))) (aref generations slot)))
    (loop with slot of-type fixnum = (handle-table-free jids) while (>= slot 0)
          do (setf (snap-u32 buffer (+ at 20 (* 4 count) (* 4 nfree))) slot)
             (incf nfree)
             (setf slot (aref (handle-table-local jids) slot)))
    (setf (snap-u32 buffer (+ at 8)) nfree)
    (with-joint-columns (kind flags handle body-a body-b ax ay az bx by bz rest-length min-length max-length
                         hertz damping-ratio break-force impulse-x impulse-y impulse-z)
        rows
      (dotimes (row n)
        (let ((o (+ at 20 (* 4 count) (* 4 nfree) (* row +snapshot-joint-bytes+)))
              (a (aref body-a row)) (b (aref body-b row)))
          (declare (type index o))
          (setf (snap-u32 buffer o) (aref kind row) (snap-u32 buffer (+ o 4)) (aref flags row)
                (snap-u32 buffer (+ o 8)) (handle-index (ldb (byte +handle-joint-bit+ 0) (aref handle row)))
                (snap-u32 buffer (+ o 12)) (handle-index a) (snap-u32 buffer (+ o 16)) (handle-generation a)
                (snap-u32 buffer (+ o 20)) (if (= b +no-body+) #xFFFFFFFF (handle-index b))
                (snap-u32 buffer (+ o 24)) (if (= b +no-body+) 0 (handle-generation b)))
          (macrolet ((floats (&rest columns)
                       `(setf ,@(loop for c in columns for k from 28 by 4
                                      append `((snap-f32 buffer (+ o ,k)) (aref ,c row))))))
            (floats ax ay az bx by bz rest-length min-length max-length hertz damping-ratio
                    break-force impulse-x impulse-y impulse-z)))))))
;; Joints in a snapshot:1 ends here

;; [[file:../physics.org::#SNJOIN][Joints in a snapshot:2]]
(defun apply-snapshot-joints (world buffer scratch)
  "Make WORLD's joint set the checked snapshot BUFFER's: none when it has no joint part (the joint
events out of the event mask again unless its features record them), else the rows, their
handle table, each body's count of joints, and the groups, stale, to be found again. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let ((at (aref (snapshot-scratch-offsets scratch) 10))
        (bits (logior (ash 1 +event-joint-break+) (ash 1 +event-joint-removed+))))
    (declare (type index at) (type fixnum bits))
    (if (minusp (aref (snapshot-scratch-sizes scratch) 10))
        (when (physics-world-joints world)
          (setf (physics-world-joints world) nil
                (slot-value world 'event-mask)
                (logior (logandc2 (world-event-mask world) bits)
                        (logand bits (the fixnum (feature-event-mask (world-features world)))))))
        (let* ((set (ensure-joint-set world)) (jids (joint-set-ids set)) (rows (joint-set-rows set))
               (n (snap-u32 buffer at)) (count (snap-u32 buffer (+ at 4))) (nfree (snap-u32 buffer (+ at 8)))
               (tag (handle-table-tag (physics-world-ids world)))
               (bodies (handle-table-generation (physics-world-ids world))))
          (declare (type index n count nfree) (type fixnum-column bodies))
          (when (< (length (handle-table-set jids)) count)
            (let ((size (max 16 (* 2 count))))
              (setf (handle-table-set jids) (make-array size :element-type 'fixnum :initial-element +set-free+)
                    (handle-table-local jids) (make-array size :element-type 'fixnum :initial-element -1)
                    (handle-table-generation jids) (make-array size :element-type 'fixnum :initial-element 0))))
          (let ((sets (handle-table-set jids)) (locals (handle-table-local jids)) (generations (handle-table-generation jids)))
            (declare (type fixnum-column sets locals generations))
            (fill sets +set-free+) (fill locals -1) (fill generations 0)
            (dotimes (slot count) (setf (aref generations slot) (snap-u32 buffer (+ at 20 (* 4 slot)))))
            (setf (handle-table-count jids) count (handle-table-tag jids) tag
                  (handle-table-free jids) (if (plusp nfree) (snap-u32 buffer (+ at 20 (* 4 count))) -1))
            (dotimes (k nfree)
              (setf (aref locals (snap-u32 buffer (+ at 20 (* 4 count) (* 4 k))))
                    (if (< (1+ k) nfree) (snap-u32 buffer (+ at 24 (* 4 count) (* 4 k))) -1)))
            (joint-columns-clear rows)
            (joint-columns-ensure-capacity rows n)
            (setf (joint-columns-length rows) n)
            (with-joint-columns (kind flags handle body-a body-b ax ay az bx by bz rest-length min-length max-length
                                 hertz damping-ratio break-force impulse-x impulse-y impulse-z row-a)
                rows
              (dotimes (row n)
                (let* ((o (+ at 20 (* 4 count) (* 4 nfree) (* row +snapshot-joint-bytes+)))
                       (slot (snap-u32 buffer (+ o 8))) (a (snap-u32 buffer (+ o 12))) (b (snap-u32 buffer (+ o 20))))
                  (declare (type index o slot a b))
                  (setf (aref kind row) (snap-u32 buffer o) (aref flags row) (snap-u32 buffer (+ o 4))
                        (aref handle row) (logior (ash 1 +handle-joint-bit+) (make-handle tag (aref generations slot) slot))
                        (aref body-a row) (make-handle tag (aref bodies a) a)
                        (aref body-b row) (if (= b #xFFFFFFFF) +no-body+ (make-handle tag (aref bodies b) b))
                        (aref row-a row) -1
                        (aref sets slot) +set-awake+ (aref locals slot) row)
                  (macrolet ((floats (&rest columns)
                               `(setf ,@(loop for c in columns for k from 28 by 4
                                              append `((aref ,c row) (snap-f32 buffer (+ o ,k)))))))
                    (floats ax ay az bx by bz rest-length min-length max-length hertz damping-ratio
                            break-force impulse-x impulse-y impulse-z))))))
          (setf (joint-set-limit-bias set) (snap-f32 buffer (+ at 12)) (joint-set-limit-mass set) (snap-f32 buffer (+ at 16)))
          ;; each body's count of joints, and the groups found again from the joints at the next need
          (ensure-joint-slots world set)
          (let ((counts (joint-set-counts set)) (parent (joint-set-parent set)))
            (declare (type fixnum-column counts parent))
            (fill counts 0)
            (dotimes (i (length parent)) (setf (aref parent i) i))
            (dotimes (row n)
              (incf (aref counts (handle-index (aref (joint-columns-body-a rows) row))))
              (let ((b (aref (joint-columns-body-b rows) row)))
                (unless (= b +no-body+) (incf (aref counts (handle-index b)))))))
          (setf (joint-set-groups-stale set) t)))))
;; Joints in a snapshot:2 ends here

;; [[file:../physics.org::#SNJOIN][Joints in a snapshot:3]]
(defun check-snapshot-jointed-flags (buffer scratch named mark)
  "Refuse the snapshot in BUFFER unless each body's jointed flag is set exactly when its slot is
marked MARK in NAMED, the slots some joint names. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch) (type fixnum-column named) (type fixnum mark)
           #.+kernel-policy+)
  (dolist (id '(3 4))
    (let* ((bat (aref (snapshot-scratch-offsets scratch) id)) (n (snap-u32 buffer bat))
           (w (material-index-bytes (snap-u32 buffer (aref (snapshot-scratch-offsets scratch) 5)))))
      (declare (type index bat n))
      (dotimes (row n)
        (let ((o (+ bat (body-part-column n 18 w) (* 2 row)))
              (slot (snap-u32 buffer (+ bat (body-part-column n 16) (* 4 row)))))
          (snapshot-check (eq (logtest +flag-jointed+ (snap-u16 buffer o)) (= (aref named slot) mark))
                          physics-snapshot-other-layout o
                          "the jointed flag set exactly on a body some joint names" (snap-u16 buffer o)))))))

(defun snapshot-joint-first (buffer at)
  "Where the first joint's record begins in the joints part at AT of BUFFER. #SNJOIN"
  (declare (type octets buffer) (type index at))
  (+ at 20 (* 4 (snap-u32 buffer (+ at 4))) (* 4 (snap-u32 buffer (+ at 8)))))

(defun check-snapshot-joint-table (buffer scratch)
  "Check the head of the joints part of the snapshot in BUFFER: the feature :joints, a joint table
of under 2^24 slots each free or held by a joint, the size its counts give, finite softness of
the limits, and every generation under 2^20. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (let* ((offsets (snapshot-scratch-offsets scratch)) (at (aref offsets 10)) (wat (aref offsets 1))
         (n (snap-u32 buffer at)) (count (snap-u32 buffer (+ at 4))) (nfree (snap-u32 buffer (+ at 8))))
    (declare (type index at wat))
    (snapshot-check (logbitp (position :joints +physics-features+) (snap-u32 buffer (+ wat 4)))
                    physics-snapshot-other-layout (+ wat 4) "the feature :joints of a world with joints"
                    (snap-u32 buffer (+ wat 4)))
    (snapshot-check (< count (ash 1 +handle-index-bits+)) physics-snapshot-other-layout (+ at 4)
                    "a joint table of under 2^24 slots" count)
    (snapshot-check (= (+ n nfree) count) physics-snapshot-other-layout (+ at 8)
                    "a joint for each slot that is not free" nfree)
    (check-part-size scratch 10 (+ 20 (* 4 count) (* 4 nfree) (* +snapshot-joint-bytes+ n)))
    (snap-finite-f32 buffer (+ at 12))
    (snap-finite-f32 buffer (+ at 16))
    (dotimes (slot count)
      (snapshot-check (< (snap-u32 buffer (+ at 20 (* 4 slot))) (ash 1 +handle-generation-bits+))
                      physics-snapshot-other-layout (+ at 20 (* 4 slot)) "a generation under 2^20"
                      (snap-u32 buffer (+ at 20 (* 4 slot)))))))

(defun mark-snapshot-bodies (buffer scratch slots)
  "Mark in SCRATCH's marks, room made for SLOTS, the slot of every body of the snapshot in
BUFFER; return the marks and the mark. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch) (type index slots))
  (multiple-value-bind (marks stamp) (snapshot-marks scratch slots)
    (declare (type fixnum-column marks) (type fixnum stamp))
    (dolist (id '(3 4))
      (let* ((bat (aref (snapshot-scratch-offsets scratch) id)) (n (snap-u32 buffer bat)))
        (dotimes (row n)
          (setf (aref marks (snap-u32 buffer (+ bat (body-part-column n 16) (* 4 row)))) (1+ stamp)))))
    (values marks (1+ stamp))))

(defun check-snapshot-joint-bodies (buffer o hat bodies marks live)
  "Refuse the joint record at O of BUFFER unless both its bodies are live bodies of the snapshot
(marked LIVE in MARKS, within the BODIES slots of the handle part at HAT) of the generation that
part gives, two bodies, not one; the second may be none, a fixed point. #SNJOIN"
  (declare (type octets buffer) (type index o hat bodies) (type fixnum-column marks) (type fixnum live))
  (loop for side in '(12 20)
        for slot = (snap-u32 buffer (+ o side))
        for generation = (snap-u32 buffer (+ o side 4))
        unless (and (= side 20) (= slot #xFFFFFFFF) (zerop generation))
          do (snapshot-check (and (< slot bodies) (= (aref marks slot) live)
                                  (= generation (snap-u32 buffer (+ hat 8 (* 4 slot))))
                                  (or (= side 12) (/= slot (snap-u32 buffer (+ o 12)))))
                             physics-snapshot-other-layout (+ o side)
                             "the slot of a live body of the snapshot, of its generation, not the joint's other body"
                             slot)))
;; Joints in a snapshot:3 ends here

;; [[file:../physics.org::#SNJOIN][Joints in a snapshot:4]]
(defun check-snapshot-joint-numbers (buffer o reach)
  "Refuse the joint record at O of BUFFER unless its kind and flags are a joint's and each number
is finite and in its range: anchors within REACH (a fixed point within the coordinate limit),
lengths, softness and break force of 0 or more up to their largest, carried impulses up to
10^9 N s. #SNJOIN"
  (declare (type octets buffer) (type index o) (type single-float reach))
  (snapshot-check (<= (snap-u32 buffer o) +joint-distance+) physics-snapshot-other-layout o
                  "a joint kind, 0 or 1" (snap-u32 buffer o))
  (snapshot-check (< (snap-u32 buffer (+ o 4)) 16) physics-snapshot-other-layout (+ o 4)
                  "joint flags under 16" (snap-u32 buffer (+ o 4)))
  (let ((fixed (= (snap-u32 buffer (+ o 20)) #xFFFFFFFF)))
    (flet ((ranged (k low high what)
             (let ((v (snap-finite-f32 buffer (+ o k))))
               (snapshot-check (<= low v high) physics-snapshot-other-layout (+ o k) what v)
               v)))
      (loop for k from 28 below 40 by 4
            do (ranged k (- reach) reach "an anchor within the reach of the world's largest radius"))
      (loop for k from 40 below 52 by 4
            do (if fixed
                   (ranged k (- +physics-coordinate-limit+) +physics-coordinate-limit+
                           "a fixed point within the coordinate limit")
                   (ranged k (- reach) reach "an anchor within the reach of the world's largest radius")))
      (loop for k from 52 below 64 by 4
            do (ranged k 0.0 +physics-max-joint-length+ "a length from 0 to the longest a joint may have"))
      ;; a hertz of a few denormals would make the softness divide by zero
      (let ((hertz (ranged 64 0.0 1000.0 "a hertz from 0 to 1000")))
        (snapshot-check (or (= hertz 0.0) (>= hertz +physics-min-joint-hertz+)) physics-snapshot-other-layout (+ o 64)
                        "a hertz of 0, or of 0.001 (+physics-min-joint-hertz+) or more" hertz))
      (ranged 68 0.0 1000.0 "a damping ratio from 0 to 1000")
      (ranged 72 0.0 +physics-max-break-force+ "a break force from 0 to the largest")
      (loop for k from 76 below 88 by 4
            do (ranged k -1e9 1e9 "a carried impulse up to 1e9 N s")))))

(defun check-snapshot-joint-rows (buffer scratch)
  "Check each joint record of the snapshot in BUFFER: its bodies (check-snapshot-joint-bodies)
and its numbers (check-snapshot-joint-numbers). #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (let* ((offsets (snapshot-scratch-offsets scratch)) (at (aref offsets 10)) (hat (aref offsets 2))
         (bodies (snap-u32 buffer hat)) (first (snapshot-joint-first buffer at))
         (reach (* +joint-anchor-reach+ (snap-f32 buffer (+ (aref offsets 1) 48)))))
    (declare (type index at hat bodies first))
    (multiple-value-bind (marks live) (mark-snapshot-bodies buffer scratch (max bodies (snap-u32 buffer (+ at 4))))
      (dotimes (row (snap-u32 buffer at))
        (let ((o (+ first (* row +snapshot-joint-bytes+))))
          (check-snapshot-joint-numbers buffer o reach)
          (check-snapshot-joint-bodies buffer o hat bodies marks live))))))

(defun check-snapshot-joint-names (buffer scratch)
  "Refuse the snapshot in BUFFER unless a body's jointed flag is set exactly when some joint of
its joints part names it. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (let* ((at (aref (snapshot-scratch-offsets scratch) 10)) (first (snapshot-joint-first buffer at)))
    (multiple-value-bind (named stamp) (snapshot-marks scratch (snap-u32 buffer (aref (snapshot-scratch-offsets scratch) 2)))
      (declare (type fixnum-column named) (type fixnum stamp))
      (dotimes (row (snap-u32 buffer at))
        (let ((o (+ first (* row +snapshot-joint-bytes+))))
          (setf (aref named (snap-u32 buffer (+ o 12))) (1+ stamp))
          (unless (= (snap-u32 buffer (+ o 20)) #xFFFFFFFF)
            (setf (aref named (snap-u32 buffer (+ o 20))) (1+ stamp)))))
      (check-snapshot-jointed-flags buffer scratch named (1+ stamp)))))

(defun check-snapshot-joint-slots (buffer scratch)
  "Refuse the snapshot in BUFFER unless each free joint slot is listed once and each live one is
held by one joint. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (let* ((at (aref (snapshot-scratch-offsets scratch) 10)) (count (snap-u32 buffer (+ at 4)))
         (first (snapshot-joint-first buffer at)))
    (multiple-value-bind (marks stamp) (snapshot-marks scratch count)
      (declare (type fixnum-column marks) (type fixnum stamp))
      (flet ((take (o what)
               (let ((slot (snap-u32 buffer o)))
                 (snapshot-check (and (< slot count) (< (aref marks slot) stamp)) physics-snapshot-other-layout o
                                 what slot)
                 (setf (aref marks slot) stamp))))
        (dotimes (k (snap-u32 buffer (+ at 8)))
          (take (+ at 20 (* 4 count) (* 4 k)) "a free joint slot of the table, listed once"))
        (dotimes (row (snap-u32 buffer at))
          (take (+ first (* row +snapshot-joint-bytes+) 8) "a joint slot of the table, neither free nor another joint's"))))))

(defun check-snapshot-joints (buffer scratch)
  "Check the joint part of the snapshot in BUFFER, when it has one, stage by stage: its table, each
joint's record, the bodies' jointed flags and the joint slots; without one, that no body is
flagged jointed. #SNJOIN"
  (declare (type octets buffer) (type snapshot-scratch scratch))
  (if (minusp (aref (snapshot-scratch-sizes scratch) 10))
      (check-snapshot-jointed-flags buffer scratch (snapshot-scratch-marks scratch) -1)
      (progn
        (check-snapshot-joint-table buffer scratch)
        (check-snapshot-joint-rows buffer scratch)
        (check-snapshot-joint-names buffer scratch)
        (check-snapshot-joint-slots buffer scratch))))
;; Joints in a snapshot:4 ends here

;; [[file:../physics.org::#SNBOXB][Box bodies in a snapshot:1]]
(defun write-snapshot-box-bodies (world buffer at)
  "Write the box part of WORLD's snapshot into BUFFER from AT: the counts of box bodies and of the
last step's points, each box's slot, half-extents, first point and count, then the points' keys
and their three carried impulses, each a column copied whole; return its bytes. #SNBOXB"
  (declare (type octets buffer) (type index at) #.+kernel-policy+)
  (let* ((set (physics-world-box-bodies world)) (points (box-set-points set))
         (p (box-point-columns-length points))
         (hx (box-set-hx set)) (hy (box-set-hy set)) (hz (box-set-hz set))
         (first (box-set-first set)) (count (box-set-count set))
         (slots (min (length hx) (handle-table-count (physics-world-ids world)))) (b 0))
    (declare (type box-set set) (type index p slots b) (type f32-column hx hy hz) (type fixnum-column first count))
    (dotimes (slot slots)
      (when (plusp (aref hx slot))
        (let ((o (+ at 8 (* b +snapshot-box-body-bytes+))))
          (declare (type index o))
          (setf (snap-u32 buffer o) slot (snap-f32 buffer (+ o 4)) (aref hx slot)
                (snap-f32 buffer (+ o 8)) (aref hy slot) (snap-f32 buffer (+ o 12)) (aref hz slot)
                (snap-u32 buffer (+ o 16)) (if (zerop (aref count slot)) 0 (ldb (byte 32 0) (aref first slot)))
                (snap-u32 buffer (+ o 20)) (ldb (byte 32 0) (aref count slot)))
          (incf b))))
    (setf (snap-u32 buffer at) b (snap-u32 buffer (+ at 4)) p)
    (let ((o (+ at 8 (* b +snapshot-box-body-bytes+))))
      (declare (type index o))
      (sb-kernel:%byte-blt (box-point-columns-key points) 0 buffer o (+ o (* 8 p)))
      (sb-kernel:%byte-blt (box-point-columns-normal-impulse points) 0 buffer (+ o (* 8 p)) (+ o (* 12 p)))
      (sb-kernel:%byte-blt (box-point-columns-tangent-impulse-1 points) 0 buffer (+ o (* 12 p)) (+ o (* 16 p)))
      (sb-kernel:%byte-blt (box-point-columns-tangent-impulse-2 points) 0 buffer (+ o (* 16 p)) (+ o (* 20 p))))
    (box-part-bytes b p)))
;; Box bodies in a snapshot:1 ends here

;; [[file:../physics.org::#SNBOXB][Box bodies in a snapshot:2]]
(defun check-snapshot-box-records (buffer scratch marks mark)
  "Check the head and the box records of the box part of the snapshot in BUFFER: the feature
:box-bodies, the size its counts give, each box's slot within the table and listed once (marked
MARK in MARKS), its half-extents finite, each at least +box-min-half-extent+ and the half
diagonal within the world's largest radius, and its points within the part's. #SNBOXB"
  (declare (type octets buffer) (type snapshot-scratch scratch) (type fixnum-column marks) (type fixnum mark))
  (let* ((offsets (snapshot-scratch-offsets scratch)) (at (aref offsets 11)) (wat (aref offsets 1))
         (b (snap-u32 buffer at)) (p (snap-u32 buffer (+ at 4))) (count (snap-u32 buffer (aref offsets 2)))
         (max-radius (snap-f32 buffer (+ wat 48))))
    (declare (type index at wat count) (type (unsigned-byte 32) b p))
    (snapshot-check (logbitp (position :box-bodies +physics-features+) (snap-u32 buffer (+ wat 4)))
                    physics-snapshot-other-layout (+ wat 4) "the feature :box-bodies of a world with boxes"
                    (snap-u32 buffer (+ wat 4)))
    (snapshot-check (<= b count) physics-snapshot-other-layout at "no more boxes than slots" b)
    (snapshot-check (< p (ash 1 26)) physics-snapshot-other-layout (+ at 4) "under 2^26 points" p)
    (check-part-size scratch 11 (box-part-bytes b p))
    (dotimes (k b)
      (let* ((o (+ at 8 (* k +snapshot-box-body-bytes+))) (slot (snap-u32 buffer o)))
        (snapshot-check (and (< slot count) (/= (aref marks slot) mark)) physics-snapshot-other-layout o
                        "a box's slot of the table, listed once" slot)
        (setf (aref marks slot) mark)
        (let ((hx (snap-finite-f32 buffer (+ o 4))) (hy (snap-finite-f32 buffer (+ o 8)))
              (hz (snap-finite-f32 buffer (+ o 12))))
          ;; each extent bounded first, so that the half diagonal's squares cannot overflow
          (snapshot-check (and (<= +box-min-half-extent+ (min hx hy hz)) (<= (max hx hy hz) max-radius)
                               (<= (box-half-diagonal hx hy hz) max-radius))
                          physics-snapshot-other-layout (+ o 4)
                          "half-extents of at least the smallest, the half diagonal within the world's largest radius"
                          (list hx hy hz)))
        (snapshot-check (<= (+ (snap-u32 buffer (+ o 16)) (snap-u32 buffer (+ o 20))) p)
                        physics-snapshot-other-layout (+ o 16) "a box's points among the part's"
                        (list (snap-u32 buffer (+ o 16)) (snap-u32 buffer (+ o 20))))))))

(defun check-snapshot-box-bodies (buffer scratch)
  "Check the box part of the snapshot in BUFFER, when it has one: its records
(check-snapshot-box-records), every point's key a fixnum's word and every carried impulse finite
and of at most 10^9 N s; and, with it or without it, that a body has the box flag exactly when the
part lists its slot. #SNBOXB"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (let* ((offsets (snapshot-scratch-offsets scratch)) (at (aref offsets 11))
         (present (>= (aref (snapshot-scratch-sizes scratch) 11) 0))
         (boxes (if present (snap-u32 buffer at) 0)) (flagged 0))
    (declare (type index at boxes flagged))
    (multiple-value-bind (marks stamp) (snapshot-marks scratch (snap-u32 buffer (aref offsets 2)))
      (declare (type fixnum-column marks) (type fixnum stamp))
      (when present
        (check-snapshot-box-records buffer scratch marks (1+ stamp))
        (let* ((p (snap-u32 buffer (+ at 4))) (keys (+ at 8 (* boxes +snapshot-box-body-bytes+)))
               (impulses (+ keys (* 8 p)))
               (wrong (snapshot-words-within buffer impulses (+ impulses (* 12 p)) (sb-kernel:single-float-bits 1e9))))
          (declare (type index p keys impulses))
          (dotimes (k p)
            (snapshot-check (not (logtest 1 (snap-u64 buffer (+ keys (* 8 k))))) physics-snapshot-other-layout
                            (+ keys (* 8 k)) "a point's key, a fixnum's word" (snap-u64 buffer (+ keys (* 8 k)))))
          (snapshot-check (null wrong) physics-snapshot-other-layout wrong "a carried impulse of at most 10^9 N s"
                          (and wrong (snap-f32 buffer wrong)))))
      (dolist (id '(3 4))
        (let* ((bat (aref offsets id)) (n (snap-u32 buffer bat))
               (w (material-index-bytes (snap-u32 buffer (aref offsets 5)))))
          (declare (type index bat n))
          (dotimes (row n)
            (let ((o (+ bat (body-part-column n 18 w) (* 2 row)))
                  (slot (snap-u32 buffer (+ bat (body-part-column n 16) (* 4 row)))))
              (when (logtest +flag-box-shape+ (snap-u16 buffer o)) (incf flagged))
              (snapshot-check (eq (logtest +flag-box-shape+ (snap-u16 buffer o)) (= (aref marks slot) (1+ stamp)))
                              physics-snapshot-other-layout o
                              "the box flag set exactly on a body whose slot the box part lists" (snap-u16 buffer o))))))
      (snapshot-check (= flagged boxes) physics-snapshot-other-layout at "a body for each box the part lists" boxes))))
;; Box bodies in a snapshot:2 ends here

;; [[file:../physics.org::#SNBOXB][Box bodies in a snapshot:3]]
(defun apply-snapshot-box-bodies (world buffer scratch)
  "Make WORLD's box set the checked snapshot BUFFER's: none when it has no box part; else the
half-extents by slot, zero where a slot holds no box, each box's first point and count, and the
last step's points, their keys and carried impulses, every other number of a point zero. #SNBOXB"
  (declare (type octets buffer) (type snapshot-scratch scratch) #.+kernel-policy+)
  (if (minusp (aref (snapshot-scratch-sizes scratch) 11))
      (setf (physics-world-box-bodies world) nil)
      (let* ((at (aref (snapshot-scratch-offsets scratch) 11))
             (b (snap-u32 buffer at)) (p (snap-u32 buffer (+ at 4)))
             (set (or (physics-world-box-bodies world) (setf (physics-world-box-bodies world) (%make-box-set))))
             (points (box-set-points set))
             (o (+ at 8 (* b +snapshot-box-body-bytes+))))
        (declare (type index at b p o) (type box-set set))
        (box-set-room set (handle-table-count (physics-world-ids world)))
        (fill (box-set-hx set) 0.0) (fill (box-set-hy set) 0.0) (fill (box-set-hz set) 0.0)
        (fill (box-set-count set) 0) (fill (box-set-previous-count set) 0)
        (box-point-columns-clear (box-set-previous set))
        (box-point-columns-clear points)
        (box-point-columns-ensure-capacity points p)
        (setf (box-point-columns-length points) p)
        (sb-kernel:%byte-blt buffer o (box-point-columns-key points) 0 (* 8 p))
        (sb-kernel:%byte-blt buffer (+ o (* 8 p)) (box-point-columns-normal-impulse points) 0 (* 4 p))
        (sb-kernel:%byte-blt buffer (+ o (* 12 p)) (box-point-columns-tangent-impulse-1 points) 0 (* 4 p))
        (sb-kernel:%byte-blt buffer (+ o (* 16 p)) (box-point-columns-tangent-impulse-2 points) 0 (* 4 p))
        (dotimes (k b)
          (let ((r (+ at 8 (* k +snapshot-box-body-bytes+))))
            (declare (type index r))
            (let ((slot (snap-u32 buffer r)))
              (setf (aref (box-set-hx set) slot) (snap-f32 buffer (+ r 4))
                    (aref (box-set-hy set) slot) (snap-f32 buffer (+ r 8))
                    (aref (box-set-hz set) slot) (snap-f32 buffer (+ r 12))
                    (aref (box-set-first set) slot) (snap-u32 buffer (+ r 16))
                    (aref (box-set-count set) slot) (snap-u32 buffer (+ r 20))))))
        (setf (box-set-live set) b))))
;; Box bodies in a snapshot:3 ends here

;; [[file:../physics.org::#SNBOXB][Box bodies in a snapshot:4]]
(defun snapshot-box-tower (kernels)
  "A floor world under KERNELS with a tower of five boxes dropped from a little apart, the
second turned, the fourth flat and long, and two balls falling beside and onto it: boxes meet
the floor, each other and the balls within its first second. Return the world and the boxes'
handles. #SNBOXB"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -8 -8 -8 16 16 16 nil)
    (fill-terrain terrain -8 -1 -8 16 0 16 t)
    (let ((world (make-physics-world :terrain terrain :kernels kernels)))
      (values
       world
       (loop for (y hx hy hz orientation) in '((0.5 0.3 0.3 0.3 (1 0 0 0)) (1.3 0.3 0.3 0.3 (0.97 0 0.24 0))
                                              (2.1 0.3 0.3 0.3 (1 0 0 0)) (2.8 0.5 0.15 0.3 (0.99 0.1 0 0))
                                              (3.5 0.25 0.25 0.25 (1 0 0 0)))
             collect (add-physics-box world 2.5 y 2.5 hx hy hz :density 500 :orientation orientation)
             finally (add-physics-body world 2.55 4.6 2.45 :radius 0.2)
                     (add-physics-body world 3.3 1.0 2.5 :radius 0.25 :vx -1.0))))))
;; Box bodies in a snapshot:4 ends here

;; [[file:../physics.org::#K5DF9S][Scenes are definitions:2]]
(defun physics-world-handles (world)
  "The handles of WORLD's bodies, as a list: the awake rows in order, then the sleeping ones; for
a scene's world before its first step, the order its bodies were added in. #K5DF9S"
  (check-world world 'physics-world-handles)
  (loop for buffer in (list (physics-world-awake world) (physics-world-sleeping world))
        nconc (loop for row below (body-columns-length buffer)
                    collect (aref (body-columns-handle buffer) row))))
;; Scenes are definitions:2 ends here

;; [[file:../physics.org::#JAU0EF][Kinds of body, and the springs that emit them:1]]
(defparameter *physics-body-kinds*
  '((:ball        :radius 0.25 :mass 0.5   :restitution 0.6 :friction 0.6 :life nil)
    (:marble      :radius 0.08 :mass 0.02  :restitution 0.4 :friction 0.4 :life 30)
    (:water-drop  :radius 0.06 :mass 0.005 :restitution 0.0 :friction 0.1 :life 2.6
                  :collide-with-bodies nil)
    (:lava-gobbet :radius 0.12 :mass 0.05  :restitution 0.1 :friction 0.8 :life 4))
  "The kinds of body, each a keyword and the keyword arguments it gives add-physics-body; a
body's kind number is its kind's place in this list, from 1. #JAU0EF")

(defun physics-kind-number (kind world)
  "The number of KIND in *physics-body-kinds*, from 1, or an invalid-physics-parameter error
naming it. #JAU0EF"
  (let ((place (position kind *physics-body-kinds* :key #'first)))
    (unless place
      (error 'invalid-physics-parameter :world world :name :kind :value kind
                                        :expected (format nil "one of ~{~S~^ ~}"
                                                          (mapcar #'first *physics-body-kinds*))))
    (1+ place)))

(declaim (inline physics-kind-entry))
(defun physics-kind-entry (number)
  "The entry of the NUMBER-th kind of *physics-body-kinds*: its keyword, then its arguments. #JAU0EF"
  (nth (1- number) *physics-body-kinds*))

(defun add-physics-body-of-kind-number (world number x y z vx vy vz report-hits &optional (inside-cells :refuse))
  "Add a body of the NUMBER-th kind of *physics-body-kinds* and return its handle. #JAU0EF"
  (apply #'add-physics-body world x y z :kind number :vx vx :vy vy :vz vz :report-hits report-hits
         :inside-cells inside-cells (rest (physics-kind-entry number))))

(defun add-physics-body-of-kind (world kind x y z &key (vx 0.0) (vy 0.0) (vz 0.0) report-hits (inside-cells :refuse))
  "Add a body of KIND (a keyword of *physics-body-kinds*) centred at X Y Z, moving at VX VY VZ,
and return its handle; INSIDE-CELLS as for add-physics-body. #JAU0EF"
  (check-world world 'add-physics-body-of-kind)
  (add-physics-body-of-kind-number world (physics-kind-number kind world) x y z vx vy vz report-hits inside-cells))

(defun physics-body-kind-name (world handle)
  "The keyword of the kind of HANDLE's body, or NIL for a body added without a kind. #JAU0EF"
  (check-world world 'physics-body-kind-name)
  (let ((number (physics-body-kind world handle)))
    (and (<= 1 number (length *physics-body-kinds*))
         (first (physics-kind-entry number)))))

(defstruct (physics-spring (:constructor %make-physics-spring (number x y z per-step every)))
  "A block at cell X Y Z that emits PER-STEP bodies of the NUMBER-th kind of *physics-body-kinds*
on every EVERY-th call of run-physics-springs; CALLS and EMITTED count what it has done. #JAU0EF"
  (number 1 :type (integer 1 1000))
  (x 0 :type fixnum) (y 0 :type fixnum) (z 0 :type fixnum)
  (per-step 1 :type (integer 1 64)) (every 1 :type (integer 1 3600))
  (calls 0 :type fixnum) (emitted 0 :type fixnum))

(defun make-physics-spring (kind x y z &key (per-step 1) (every 1))
  "A spring of KIND at cell X Y Z emitting PER-STEP bodies every EVERY steps. #JAU0EF"
  (%make-physics-spring (physics-kind-number kind nil)
                        (check-cell :x x) (check-cell :y y) (check-cell :z z)
                        (check-count :per-step per-step 64) (check-count :every every 3600)))

(defun make-fountain (x y z)
  "A fountain at cell X Y Z: two water drops every step. #JAU0EF"
  (make-physics-spring :water-drop x y z :per-step 2))

(defun make-lava-spring (x y z)
  "A lava spring at cell X Y Z: one gobbet every fourth step. #JAU0EF"
  (make-physics-spring :lava-gobbet x y z :every 4))

(defun spring-throw (x y z count)
  "The direction (a unit vector within 20 degrees of +y) and the speed (4 to 6 m/s) of the
COUNT-th body of the spring at cell X Y Z: a fixed hash of the four integers. #JAU0EF"
  (declare (type fixnum x y z count))
  (let ((h (ldb (byte 32 0) (logxor (* (ldb (byte 26 0) x) 73856093) (* (ldb (byte 26 0) y) 19349663)
                                    (* (ldb (byte 26 0) z) 83492791) (* (ldb (byte 29 0) count) 2654435761)))))
    (declare (type (unsigned-byte 32) h))
    ;; two rounds of multiply and shift spread every input bit over the 32
    (dotimes (round 2)
      (setf h (ldb (byte 32 0) (* (logxor h (ash h -16)) 2246822507))))
    (let ((angle (* 2.0 (f32 pi) (/ (float (ldb (byte 12 0) h) 1.0) 4096.0)))
          (tilt (* (f32 (/ pi 9)) (/ (float (ldb (byte 10 12) h) 1.0) 1024.0)))
          (speed (+ 4.0 (* 2.0 (/ (float (ldb (byte 10 22) h) 1.0) 1024.0)))))
      (declare (type single-float angle tilt speed))
      (values (* (sin tilt) (cos angle)) (cos tilt) (* (sin tilt) (sin angle)) speed))))

(defun run-physics-springs (world springs &optional function)
  "Let each of SPRINGS emit into WORLD what is due this call, calling FUNCTION, when given, on
the handle of each body emitted; return how many were emitted. A spring whose mouth, the cell
above its block, is solid emits nothing. Conses nothing. #JAU0EF"
  (check-world world 'run-physics-springs)
  (unless (and (listp springs) (every #'physics-spring-p springs))
    (error 'invalid-physics-parameter :world world :name :springs :value springs
                                      :expected "a list of physics-springs (from make-physics-spring)"))
  (when function (check-function world :function function))
  (let ((emitted 0) (terrain (physics-world-terrain world)))
    (declare (type fixnum emitted))
    (dolist (spring springs emitted)
      (when (and (zerop (mod (physics-spring-calls spring) (physics-spring-every spring)))
                 ;; a spring whose mouth, the cell above its block, is solid or not resident is
                 ;; covered, and waits
                 (not (and terrain (terrain-solid-p terrain (physics-spring-x spring)
                                                    (1+ (physics-spring-y spring)) (physics-spring-z spring)))))
        (let* ((number (physics-spring-number spring))
               (radius (f32 (getf (rest (physics-kind-entry number)) :radius)))
               (x (physics-spring-x spring)) (y (physics-spring-y spring)) (z (physics-spring-z spring)))
          (declare (type single-float radius))
          (dotimes (k (physics-spring-per-step spring))
            (multiple-value-bind (dx dy dz speed) (spring-throw x y z (physics-spring-emitted spring))
              (declare (type single-float dx dy dz speed))
              (incf (physics-spring-emitted spring))
              (let ((handle (add-physics-body-of-kind-number world number (+ x 0.5) (+ y 1.0 radius 0.01) (+ z 0.5)
                                                             (* speed dx) (* speed dy) (* speed dz) nil)))
                (incf emitted)
                (when function (funcall function handle)))))))
      (incf (physics-spring-calls spring)))))
;; Kinds of body, and the springs that emit them:1 ends here

;; [[file:../physics.org::#H7P4CX][The player: a box that walks:1]]
(defparameter *physics-player-shape*
  '(:half-width 0.3d0 :height 1.8d0 :eye 1.62d0 :gravity 9.81d0 :jump-speed 5d0
    :walk-speed 4.3d0 :acceleration 40d0 :step-seconds 1/120 :steps-per-frame 8 :step-ahead 0.3d0)
  "The walker's box and constants, read when a walker is made: half width and height (cells),
eye height, gravity (m/s2), jump and walking speed (m/s), ground acceleration (m/s2), the step,
the most steps one frame runs, and how far ahead the auto-jump looks. #H7P4CX")

(defstruct (physics-player (:constructor %make-physics-player))
  "The walker: the middle of its soles X Y Z, its velocity, whether it stands on something,
whether the jump key was down at the last step, the unspent time of its frames, and its own
copy of the constants of *physics-player-shape*. #H7P4CX"
  (x 0d0 :type double-float) (y 0d0 :type double-float) (z 0d0 :type double-float)
  (vx 0d0 :type double-float) (vy 0d0 :type double-float) (vz 0d0 :type double-float)
  (grounded nil :type boolean) (jump-held nil :type boolean)
  (pending 0d0 :type double-float)
  (half-width 0.3d0 :type double-float) (height 1.8d0 :type double-float)
  (eye-height 1.62d0 :type double-float)
  (gravity 9.81d0 :type double-float) (jump-speed 5d0 :type double-float)
  (walk-speed 4.3d0 :type double-float) (acceleration 40d0 :type double-float)
  (step-seconds (/ 1d0 120) :type double-float) (steps-per-frame 8 :type (integer 1 1000))
  (step-ahead 0.3d0 :type double-float))

;; the documentation of the walker's public readers, which defstruct cannot give
(loop for (name text)
        in '((physics-player-x "The x of the middle of PLAYER's soles, in cells. #H7P4CX")
             (physics-player-y "The height of PLAYER's soles, in cells. #H7P4CX")
             (physics-player-z "The z of the middle of PLAYER's soles, in cells. #H7P4CX")
             (physics-player-vx "PLAYER's velocity along x, in cells a second. #H7P4CX")
             (physics-player-vy "PLAYER's upward velocity, in cells a second. #H7P4CX")
             (physics-player-vz "PLAYER's velocity along z, in cells a second. #H7P4CX")
             (physics-player-grounded "True when PLAYER stands on something. #H7P4CX"))
      do (setf (documentation name 'function) text))

(declaim (inline player-input))
(defun player-input (name value)
  "VALUE as a double-float, or an invalid-physics-number error naming NAME. A double-float is
checked in place and returned as it is, so the walker conses nothing for one. #H7P4CX"
  (if (and (typep value 'double-float) (not (sb-ext:float-nan-p value))
           (< (abs value) (float most-positive-single-float 1d0)))
      value
      (progn (finite-f32 name value) (coerce value 'double-float))))

(declaim (inline check-player))
(defun check-player (player)
  "PLAYER, a physics-player, or an invalid-physics-parameter error naming :player. #H7P4CX"
  (unless (physics-player-p player)
    (error 'invalid-physics-parameter :name :player :value player
                                      :expected "a physics-player (from make-physics-player)"))
  player)

(defun make-physics-player (x y z)
  "A walker standing with the middle of its soles at X Y Z. #H7P4CX"
  (flet ((coordinate (name value) (check-coordinate name (player-input name value)))
         (shape (name) (coerce (getf *physics-player-shape* name) 'double-float)))
    (%make-physics-player
     :x (coordinate :x x) :y (coordinate :y y) :z (coordinate :z z)
     :half-width (shape :half-width) :height (shape :height) :eye-height (shape :eye)
     :gravity (shape :gravity) :jump-speed (shape :jump-speed) :walk-speed (shape :walk-speed)
     :acceleration (shape :acceleration) :step-seconds (shape :step-seconds)
     :steps-per-frame (getf *physics-player-shape* :steps-per-frame)
     :step-ahead (shape :step-ahead))))

(defconstant +player-epsilon+ 1d-9
  "How far a face may sit inside a cell and still count as touching it, not overlapping. #H7P4CX")

(deftype player-coordinate ()
  "A walker's coordinate: within the coordinate limit, so its cells are fixnums. #H7P4CX"
  `(double-float ,(- (* 2d0 +physics-coordinate-limit+)) ,(* 2d0 +physics-coordinate-limit+)))

(declaim (inline box-cells-clear-p))
(defun box-cells-clear-p (terrain x0 y0 z0 x1 y1 z1)
  "True when no solid cell of TERRAIN overlaps the open box X0..X1, Y0..Y1, Z0..Z1. #H7P4CX"
  (declare (type player-coordinate x0 y0 z0 x1 y1 z1))
  (let ((e +player-epsilon+))
    (loop for i of-type fixnum from (floor (+ x0 e)) below (ceiling (- x1 e))
          always (loop for j of-type fixnum from (floor (+ y0 e)) below (ceiling (- y1 e))
                       always (loop for k of-type fixnum from (floor (+ z0 e)) below (ceiling (- z1 e))
                                    never (terrain-solid-p terrain i j k))))))

(defmacro with-player-box ((x0 y0 z0 x1 y1 z1) player &body body)
  "Run BODY with X0..Z1 bound to the corners of PLAYER's box. #H7P4CX"
  (let ((p (gensym "PLAYER")) (w (gensym "W")))
    `(let* ((,p ,player) (,w (physics-player-half-width ,p))
            (,x0 (- (physics-player-x ,p) ,w)) (,y0 (physics-player-y ,p)) (,z0 (- (physics-player-z ,p) ,w))
            (,x1 (+ (physics-player-x ,p) ,w)) (,y1 (+ (physics-player-y ,p) (physics-player-height ,p)))
            (,z1 (+ (physics-player-z ,p) ,w)))
       (declare (type player-coordinate ,x0 ,y0 ,z0 ,x1 ,y1 ,z1) (ignorable ,x0 ,y0 ,z0 ,x1 ,y1 ,z1))
       ,@body)))

(declaim (inline player-move-axis))
(defun player-move-axis (player terrain axis distance)
  "Move PLAYER along AXIS (0 x, 1 y, 2 z) by DISTANCE, or up to the first solid layer of cells in
its path; return true when a cell stopped it. #H7P4CX"
  (declare (type physics-player player) (type (integer 0 2) axis) (type (double-float -1d3 1d3) distance))
  (when (zerop distance) (return-from player-move-axis nil))
  (with-player-box (x0 y0 z0 x1 y1 z1) player
    (let* ((face (if (plusp distance)
                     (case axis (0 x1) (1 y1) (t z1))
                     (case axis (0 x0) (1 y0) (t z0))))
           (target (+ face distance))
           (e +player-epsilon+)
           (moved distance) (blocked nil))
      (declare (type player-coordinate face target) (type double-float moved))
      ;; the layer of cells C across AXIS, over the box's extent along the other two
      (flet ((layer-solid-p (c)
               (declare (type fixnum c))
               (let ((c0 (float c 1d0)) (c1 (float (1+ c) 1d0)))
                 (not (box-cells-clear-p terrain (if (= axis 0) c0 x0) (if (= axis 1) c0 y0) (if (= axis 2) c0 z0)
                                         (if (= axis 0) c1 x1) (if (= axis 1) c1 y1) (if (= axis 2) c1 z1))))))
        (declare (inline layer-solid-p))
        ;; the layers the leading face enters, nearest first
        (if (plusp distance)
            (loop for c of-type fixnum from (ceiling (- face e)) below (ceiling (- target e))
                  when (layer-solid-p c) do (setf moved (- c face) blocked t) (return))
            (loop for c of-type fixnum from (1- (floor (+ face e))) downto (floor (+ target e))
                  when (layer-solid-p c) do (setf moved (- (1+ c) face) blocked t) (return))))
      (ecase axis
        (0 (incf (physics-player-x player) moved) (when blocked (setf (physics-player-vx player) 0d0)))
        (1 (incf (physics-player-y player) moved) (when blocked (setf (physics-player-vy player) 0d0)))
        (2 (incf (physics-player-z player) moved) (when blocked (setf (physics-player-vz player) 0d0))))
      blocked)))

(defun step-physics-player (player terrain &key (move-x 0d0) (move-z 0d0) jump)
  "One 1/120 s step of PLAYER in TERRAIN with the input direction MOVE-X MOVE-Z (its length is
capped at 1) and the jump key down when JUMP. Return PLAYER. Conses nothing when the inputs are
double-floats. #H7P4CX"
  (check-player player) (check-terrain terrain)
  (let* ((dt (physics-player-step-seconds player))
         (move-x (player-input :move-x move-x)) (move-z (player-input :move-z move-z)))
    (declare (type double-float dt move-x move-z))
    (let* ((length (sqrt (the (double-float 0d0) (+ (* move-x move-x) (* move-z move-z)))))
           (scale (if (> length 1d0) (/ length) 1d0))
           (want-x (* (physics-player-walk-speed player) move-x scale))
           (want-z (* (physics-player-walk-speed player) move-z scale))
           (dvx (- want-x (physics-player-vx player))) (dvz (- want-z (physics-player-vz player)))
           (change (sqrt (the (double-float 0d0) (+ (* dvx dvx) (* dvz dvz)))))
           (most (* (physics-player-acceleration player) dt)))
      (declare (type (double-float 0d0) length change))
      ;; 1. turn the horizontal velocity towards the input, by at most the acceleration's share
      (when (> change most)
        (setf dvx (* dvx (/ most change)) dvz (* dvz (/ most change))))
      (incf (physics-player-vx player) dvx)
      (incf (physics-player-vz player) dvz)
      ;; 2. a jump on the press, from the ground
      (when (and jump (not (physics-player-jump-held player)) (physics-player-grounded player))
        (setf (physics-player-vy player) (physics-player-jump-speed player)))
      (setf (physics-player-jump-held player) (and jump t))
      ;; 3. gravity, and 4. y (by the mean of the speeds before and after it), then x, then z
      (let* ((vy0 (physics-player-vy player))
             (vy1 (decf (physics-player-vy player) (* (physics-player-gravity player) dt)))
             (dy (* 0.5d0 (+ vy0 vy1) dt))
             (falling (minusp dy))
             (y-blocked (player-move-axis player terrain 1 dy))
             (step-x (* (physics-player-vx player) dt)) (step-z (* (physics-player-vz player) dt))
             (x-blocked (player-move-axis player terrain 0 step-x))
             (z-blocked (player-move-axis player terrain 2 step-z)))
        (setf (physics-player-grounded player) (and falling y-blocked))
        ;; 5. the auto-jump: stopped while walking on the ground, and a box one cell up is clear
        (when (and (physics-player-grounded player) (or x-blocked z-blocked) (plusp length))
          (let* ((ahead (physics-player-step-ahead player))
                 (ox (if x-blocked (* ahead (signum step-x)) 0d0))
                 (oz (if z-blocked (* ahead (signum step-z)) 0d0)))
            (with-player-box (x0 y0 z0 x1 y1 z1) player
              ;; something still stands a little further on, where the box stands now (the axis
              ;; moved after the blocked one may have carried it past what blocked it), and one
              ;; cell higher it is clear
              (when (and (not (box-cells-clear-p terrain (+ x0 ox) y0 (+ z0 oz) (+ x1 ox) y1 (+ z1 oz)))
                         (box-cells-clear-p terrain (+ x0 ox) (+ y0 1d0) (+ z0 oz) (+ x1 ox) (+ y1 1d0) (+ z1 oz)))
                (setf (physics-player-vy player) (physics-player-jump-speed player)
                      (physics-player-grounded player) nil))))))))
  player)

(defun advance-physics-player (player terrain seconds &key (move-x 0d0) (move-z 0d0) jump)
  "Run PLAYER for a frame of SECONDS at 120 Hz, carrying the remainder to the next frame and
running at most eight steps, each with the input MOVE-X MOVE-Z JUMP of step-physics-player.
Return the steps run. #H7P4CX"
  (check-player player) (check-terrain terrain)
  (let ((dt (physics-player-step-seconds player)) (steps 0)
        (seconds (player-input :seconds seconds))
        (move-x (player-input :move-x move-x)) (move-z (player-input :move-z move-z)))
    (declare (type double-float dt seconds move-x move-z) (type fixnum steps))
    (when (minusp seconds)
      (error 'invalid-physics-parameter :world nil :name :seconds :value seconds :expected "not negative"))
    (setf (physics-player-pending player)
          (min (+ (physics-player-pending player) seconds)
               (* dt (physics-player-steps-per-frame player))))
    (loop while (>= (physics-player-pending player) (- dt 1d-12))
          do (step-physics-player player terrain :move-x move-x :move-z move-z :jump jump)
             (decf (physics-player-pending player) dt)
             (incf steps))
    steps))

(defun physics-player-eye (player)
  "Where the camera sits: the player's eye, as three values. #H7P4CX"
  (values (physics-player-x player) (+ (physics-player-y player) (physics-player-eye-height player))
          (physics-player-z player)))

(defun post-physics-player (world player)
  "Post PLAYER into WORLD's next step as a kinematic box moving at its velocity. #H7P4CX"
  (check-world world 'post-physics-player)
  (check-player player)
  (let ((w (physics-player-half-width player)) (h (* 0.5d0 (physics-player-height player))))
    ;; each double-float goes to post-physics-box as the single-float it would become there,
    ;; which is passed unboxed: passed as a double-float, each would be consed. The walker's
    ;; numbers are finite and far inside a single-float: it checks its input and keeps its box
    ;; within the coordinate limit.
    (post-physics-box world (f32 (physics-player-x player)) (f32 (+ (physics-player-y player) h))
                      (f32 (physics-player-z player)) (f32 w) (f32 h) (f32 w)
                      :vx (f32 (physics-player-vx player)) :vy (f32 (physics-player-vy player))
                      :vz (f32 (physics-player-vz player)) :owner player)))
;; The player: a box that walks:1 ends here

;; [[file:../physics.org::#H7P4CX][The player: a box that walks:12]]
(defmethod print-object ((player physics-player) stream)
  (print-unreadable-object (player stream :type t)
    (format stream "at (~,3F ~,3F ~,3F) moving (~,3F ~,3F ~,3F) ~:[in the air~;standing~]"
            (physics-player-x player) (physics-player-y player) (physics-player-z player)
            (physics-player-vx player) (physics-player-vy player) (physics-player-vz player)
            (physics-player-grounded player))))

(defmethod sb-impl::inspected-parts ((player physics-player))
  (values (format nil "~S~%" player) t
          (loop for slot in '(x y z vx vy vz grounded jump-held half-width height eye-height
                              jump-speed walk-speed step-ahead)
                collect (cons (string-downcase slot) (slot-value player slot)))))
;; The player: a box that walks:12 ends here

;; [[file:../physics.org::#Q5V1EW][The bodies as a query sees them:1]]
(defstruct (query-view (:constructor make-query-view ()))
  "What a query walks to find bodies, valid while WORLD's rows are as they were at its making:
the view's own grid of the awake rows, bucketed from their centres of now, with each entry's
radius and handle beside its centre in the grid's order (AWAKE-RADII, AWAKE-HANDLES); the
sleepers' grid, which holds handles, and the sleepers to test apart (SLEEPING-STRAYS); and a
terrain probe of its own. #Q5V1EW"
  (version -1 :type fixnum) (awake-count -1 :type fixnum) (sleeping-count -1 :type fixnum)
  (steps -1 :type fixnum)
  (awake-grid (make-hash-grid) :type hash-grid)
  (awake-radii (make-array 0 :element-type 'single-float) :type f32-column)
  (awake-handles (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (sleeping-grid (make-hash-grid) :type hash-grid)
  (sleeping-strays (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (sleeping-stray-count 0 :type index)
  (sleeping-stray-grid (make-hash-grid) :type hash-grid)
  (stray-x (make-array 0 :element-type 'single-float) :type f32-column)
  (stray-y (make-array 0 :element-type 'single-float) :type f32-column)
  (stray-z (make-array 0 :element-type 'single-float) :type f32-column)
  (own-sleeping (make-hash-grid) :type hash-grid)
  (marks (make-array 0 :element-type 'fixnum) :type fixnum-column)
  (probe (make-terrain-probe) :type terrain-probe)
  (terrain nil)
  (terrain-edits -1 :type fixnum)
  (search nil)
  (busy nil :type boolean))

(defun strays-allowed (n)
  "How many rows of a set of N a view tests one by one before it grids the set itself. #Q5V1EW"
  (declare (type index n))
  (max 16 (floor n 32)))

(defconstant +strays-tested-one-by-one+ 64
  "Up to this many strays a cast tests each; more are bucketed in a grid of their own. #Q5V1EW")

(defun grid-strays (world view grid buffer strays count)
  "When there are more than +strays-tested-one-by-one+ of them, bucket the COUNT rows STRAYS of
BUFFER into GRID (hashed, as the pair list buckets its loose rows: a dense box sized by scattered
strays could be huge), items the rows themselves, so a cast walks the strays near its path
instead of testing each; else leave GRID empty. #Q5V1EW"
  (declare (type query-view view) (type hash-grid grid) (type body-columns buffer)
           (type fixnum-column strays) (type index count))
  (setf (hash-grid-count grid) 0)
  (when (> count +strays-tested-one-by-one+)
  (when (< (length (query-view-stray-x view)) count)
    (let ((n (max count (* 2 (length (query-view-stray-x view))) 64)))
      (setf (query-view-stray-x view) (make-array n :element-type 'single-float)
            (query-view-stray-y view) (make-array n :element-type 'single-float)
            (query-view-stray-z view) (make-array n :element-type 'single-float))))
  (let ((xs (query-view-stray-x view)) (ys (query-view-stray-y view)) (zs (query-view-stray-z view)))
    (with-body-columns (x y z) buffer
      (dotimes (q count)
        (let ((row (aref strays q)))
          (setf (aref xs q) (aref x row) (aref ys q) (aref y row) (aref zs q) (aref z row)))))
    (hash-grid-reserve grid count)
    (build-hash-grid grid (f32 (grid-cell-size world)) count xs ys zs strays :dense-allowed nil))))

(defun view-awake (world view)
  "Grid the awake rows of WORLD into VIEW's own grid, at the world's cell size, from the centres
they have now, items their rows; beside each entry's copy of its centre, keep its radius and
handle, in the grid's order. #Q5V1EW"
  (declare (type query-view view) #.+kernel-policy+)
  (let* ((awake (physics-world-awake world))
         (n (body-columns-length awake))
         (grid (query-view-awake-grid view)))
    (declare (type index n))
    (hash-grid-reserve grid n)
    (build-hash-grid grid (f32 (grid-cell-size world)) n (body-columns-x awake) (body-columns-y awake)
                     (body-columns-z awake) (awake-row-identities world n))
    (when (< (length (query-view-awake-radii view)) n)
      (let ((room (max n (* 2 (length (query-view-awake-radii view))) 64)))
        (setf (query-view-awake-radii view) (make-array room :element-type 'single-float)
              (query-view-awake-handles view) (make-array room :element-type 'fixnum))))
    (let ((items (hash-grid-items grid)) (radii (query-view-awake-radii view))
          (handles (query-view-awake-handles view)))
      (declare (type fixnum-column items handles) (type f32-column radii))
      (with-body-columns (radius handle) awake
        (dotimes (e n)
          (let ((row (aref items e)))
            (setf (aref radii e) (aref radius row) (aref handles e) (aref handle row))))))
    view))

(defun view-sleeping (world view)
  "Point VIEW at the sleepers of WORLD: through the world's sleeping grid, which is exact unless a
body fell asleep since it was built; then the sleepers it does not hold where they lie are strays,
and when they are too many VIEW grids the sleepers itself. #Q5V1EW"
  (declare (type query-view view) #.+kernel-policy+)
  (let* ((sleeping (physics-world-sleeping world))
         (n (body-columns-length sleeping))
         (grid (physics-world-sleeping-grid world)))
    (declare (type index n))
    (setf (query-view-sleeping-grid view) grid (query-view-sleeping-stray-count view) 0
          (hash-grid-count (query-view-sleeping-stray-grid view)) 0)
    (flet ((grid-all ()
             (let ((own (query-view-own-sleeping view)))
               (build-hash-grid own (f32 (grid-cell-size world)) n (body-columns-x sleeping)
                                (body-columns-y sleeping) (body-columns-z sleeping) (body-columns-handle sleeping))
               (setf (query-view-sleeping-grid view) own))))
      ;; the settled sleeping grid alone is exact only while the fresh grid is empty and it holds
      ;; no dead entry ([[#G4R1D5][the grids]]); otherwise the view grids the sleepers itself,
      ;; without first marking which the settled grid holds where they lie
      (cond
        ((or (plusp (physics-world-fresh-count world)) (plusp (physics-world-newest-count world))
             (plusp (physics-world-settled-stale world)))
         (grid-all))
        ((physics-world-sleeping-grid-dirty world)
         (let* ((marks (setf (query-view-marks view) (fixnum-room (query-view-marks view) n :keep 0)))
                (strays (setf (query-view-sleeping-strays view) (fixnum-room (query-view-sleeping-strays view) n :keep 0)))
                (ids (physics-world-ids world))
                (sets (handle-table-set ids)) (gens (handle-table-generation ids)) (locals (handle-table-local ids))
                (items (hash-grid-items grid)) (gx (hash-grid-xs grid)) (gy (hash-grid-ys grid))
                (gz (hash-grid-zs grid))
                (count 0))
           (declare (type fixnum-column marks strays) (type index count))
           (fill marks 0 :end n)
           (with-body-columns (x y z) sleeping
             (dotimes (e (hash-grid-count grid))
               (let* ((h (aref items e)) (slot (handle-index h)))
                 (when (and (= (aref sets slot) +set-sleeping+) (= (aref gens slot) (handle-generation h)))
                   (let ((row (aref locals slot)))
                     (when (and (= (aref x row) (aref gx e)) (= (aref y row) (aref gy e)) (= (aref z row) (aref gz e)))
                       (setf (aref marks row) 1)))))))
           (dotimes (row n)
             (when (zerop (aref marks row))
               (setf (aref strays count) row count (1+ count))))
           (if (> count (strays-allowed n))
               (grid-all)
               (progn
                 (setf (query-view-sleeping-stray-count view) count)
                 (grid-strays world view (query-view-sleeping-stray-grid view) sleeping strays count)))))))
    view))

(defun world-query-view (world)
  "WORLD's query view, made again if any row moved, appeared or went since it was made. #Q5V1EW"
  (let ((view (or (physics-world-query-view world)
                  (setf (physics-world-query-view world) (make-query-view)))))
    (declare (type query-view view))
    (unless (and (= (query-view-version view) (physics-world-rows-version world))
                 (= (query-view-steps view) (physics-world-step-count world))
                 (= (query-view-awake-count view) (body-columns-length (physics-world-awake world)))
                 (= (query-view-sleeping-count view) (body-columns-length (physics-world-sleeping world))))
      (view-awake world view)
      (view-sleeping world view)
      (setf (query-view-version view) (physics-world-rows-version world)
            (query-view-steps view) (physics-world-step-count world)
            (query-view-awake-count view) (body-columns-length (physics-world-awake world))
            (query-view-sleeping-count view) (body-columns-length (physics-world-sleeping world))))
    (let ((terrain (physics-world-terrain world)))
      (unless (and (eq terrain (query-view-terrain view))
                   (or (null terrain) (= (voxel-terrain-edits terrain) (query-view-terrain-edits view))))
        (reset-terrain-probe (query-view-probe view) terrain)
        (setf (query-view-terrain view) terrain
              (query-view-terrain-edits view) (if terrain (voxel-terrain-edits terrain) -1))))
    view))

(declaim (inline dsqrt))

(defun dsqrt (x)
  "The square root of the non-negative double X. #Q5V1EW"
  (declare (type double-float x))
  (sqrt (the (double-float 0d0) x)))

(declaim (inline dcell))

(defun dcell (v)
  "The floor of the double V, clamped to +-4e6, as a fixnum. #Q5V1EW"
  (declare (type double-float v))
  (let* ((c (max -4d6 (min 4d6 v)))
         (i (truncate c)))
    (declare (type (double-float -4d6 4d6) c) (type fixnum i))
    (if (< c (float i 1d0)) (1- i) i)))

(defmacro do-grid-box ((item grid x0 y0 z0 x1 y1 z1) &body body)
  "Run BODY with ITEM bound to each item of GRID bucketed in a cell that meets the box from X0 Y0 Z0
to X1 Y1 Z1 (doubles, in metres), as do-grid-cells visits them; ITEM may be a list (ITEM ENTRY),
ENTRY then bound to the item's place in the grid's order. #Q5V1EW"
  (let ((g (gensym "GRID")) (inv (gensym "INV")))
    `(let* ((,g ,grid) (,inv (float (hash-grid-inv-cell ,g) 1d0)))
       (do-grid-cells (,(if (consp item) item (list item)) ,g)
           ((dcell (* ,x0 ,inv)) (dcell (* ,y0 ,inv)) (dcell (* ,z0 ,inv))
            (dcell (* ,x1 ,inv)) (dcell (* ,y1 ,inv)) (dcell (* ,z1 ,inv)))
         ,@body))))

(declaim (inline grid-box-cells))

(defun grid-box-cells (grid x0 y0 z0 x1 y1 z1)
  "How many cells of GRID the box from X0 Y0 Z0 to X1 Y1 Z1 meets (a dense grid: within its own
box), as a double. #Q5V1EW"
  (declare (type hash-grid grid) (type double-float x0 y0 z0 x1 y1 z1))
  (let ((inv (float (hash-grid-inv-cell grid) 1d0)))
    (flet ((span (a b lo n)
             (declare (type double-float a b) (type fixnum lo n))
             (let ((i0 (dcell (* a inv))) (i1 (dcell (* b inv))))
               (when (hash-grid-dense grid) (setf i0 (max i0 lo) i1 (min i1 (+ lo n -1))))
               (float (max 0 (1+ (- i1 i0))) 1d0))))
      (* (span x0 x1 (hash-grid-ox grid) (hash-grid-nx grid))
         (span y0 y1 (hash-grid-oy grid) (hash-grid-ny grid))
         (span z0 z1 (hash-grid-oz grid) (hash-grid-nz grid))))))

(declaim (inline view-row))

(defun view-row (view world handles-p item)
  "The row of the body ITEM names in a grid VIEW walks: ITEM itself for the awake grid, the row of
handle ITEM when it names a sleeper the grid holds where it lies, else -1. #Q5V1EW"
  (declare (type query-view view) (type fixnum item) #.+kernel-policy+)
  (if handles-p
      (let* ((ids (physics-world-ids world)) (slot (handle-index item)))
        (if (and (= (aref (handle-table-set ids) slot) +set-sleeping+)
                 (= (aref (handle-table-generation ids) slot) (handle-generation item)))
            (let ((row (aref (handle-table-local ids) slot)))
              (if (and (plusp (query-view-sleeping-stray-count view))
                       (zerop (aref (query-view-marks view) row)))
                  -1
                  row))
            -1))
      item))

(defmacro with-chunk-reader ((solid-p probe) &body body)
  "Run BODY with (SOLID-P X Y Z) a local function telling whether cell X Y Z is solid, through
PROBE, remembering the last chunk it looked up. #Q5V1EW"
  (let ((key (gensym "KEY")) (chunk (gensym "CHUNK")) (p (gensym "PROBE")))
    `(let ((,p ,probe) (,key -1) (,chunk +wall-chunk+))
       (declare (type terrain-probe ,p) (type fixnum ,key) (type chunk-storage ,chunk))
       (flet ((,solid-p (x y z)
                (declare (type cell x y z))
                (let ((k (chunk-key x y z)))
                  (unless (= k ,key)
                    (setf ,key k ,chunk (probe-chunk ,p k)))
                  (plusp (aref ,chunk (cell-offset x y z))))))
         (declare (inline ,solid-p))
         ,@body))))

(defmacro with-world-held ((world) &body body)
  "Run BODY with WORLD refusing edits (physics-world-busy), as it does while it steps, so a
function a query calls cannot move the rows the query walks; the world's own state is restored
however BODY ends. #Q5V1EW"
  (let ((w (gensym "WORLD")) (was (gensym "WAS")))
    `(let* ((,w ,world) (,was (physics-world-stepping ,w)))
       (unwind-protect
            (progn (unless ,was (setf (physics-world-stepping ,w) :query))
                   ,@body)
         (unless ,was (setf (physics-world-stepping ,w) nil))))))
;; The bodies as a query sees them:1 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:1]]
(defstruct (physics-hit (:constructor make-physics-hit ()))
  "The first thing a cast met: its KIND (:body, :cell or :box), the body's HANDLE (-1 for other
kinds), the box's OWNER, the cell's coordinates CELL-X CELL-Y CELL-Z, the point X Y Z, the unit
normal NX NY NZ pointing out of what was met, and the DISTANCE travelled along the cast. #C4STRY"
  (kind nil) (handle -1 :type fixnum) (owner nil)
  (cell-x 0 :type fixnum) (cell-y 0 :type fixnum) (cell-z 0 :type fixnum)
  (x 0.0 :type single-float) (y 0.0 :type single-float) (z 0.0 :type single-float)
  (nx 0.0 :type single-float) (ny 0.0 :type single-float) (nz 0.0 :type single-float)
  (distance 0.0 :type single-float))

;; the documentation of the hit's public readers and maker, which defstruct cannot give
(loop for (name text)
        in '((make-physics-hit "A physics-hit to pass as :hit, so a cast fills it instead of making one. #C4STRY")
             (physics-hit-kind "What HIT met: :body, :cell or :box. #C4STRY")
             (physics-hit-handle "The handle of the body HIT met, or -1. #C4STRY")
             (physics-hit-owner "The owner of the box HIT met (NIL for a box posted without one). #C4STRY")
             (physics-hit-cell-x "The x of the cell HIT met. #C4STRY")
             (physics-hit-cell-y "The y of the cell HIT met. #C4STRY")
             (physics-hit-cell-z "The z of the cell HIT met. #C4STRY")
             (physics-hit-x "The x of HIT's point of contact. #C4STRY")
             (physics-hit-y "The y of HIT's point of contact. #C4STRY")
             (physics-hit-z "The z of HIT's point of contact. #C4STRY")
             (physics-hit-nx "The x of HIT's unit normal, out of what was met. #C4STRY")
             (physics-hit-ny "The y of HIT's unit normal, out of what was met. #C4STRY")
             (physics-hit-nz "The z of HIT's unit normal, out of what was met. #C4STRY")
             (physics-hit-distance "How far the cast went before HIT, in metres. #C4STRY"))
      do (setf (documentation name 'function) text))

(defconstant +hit-body+ 1 "Kind code of a body hit. #C4STRY")

(defconstant +hit-cell+ 2 "Kind code of a cell hit. #C4STRY")

(defconstant +hit-box+ 3 "Kind code of a box hit. #C4STRY")

(defparameter +hit-kinds+ #(nil :body :cell :box)
  "Hit kind keywords by code. #C4STRY")
;; Casts: a search, its hits and the shapes it meets:1 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:2]]
(defstruct (query-search (:constructor make-query-search ()))
  "The state of one cast: origin O, unit direction U, the moving sphere's RADIUS (0 for a ray), the
nearest hit so far (BEST, KIND, HANDLE, BOX, CX CY CZ, N) and the candidate being weighed (CT, CN),
with the cast's choices of kinds, its excluded body or owner and its filter. #C4STRY"
  (ox 0d0 :type double-float) (oy 0d0 :type double-float) (oz 0d0 :type double-float)
  (ux 0d0 :type double-float) (uy 0d0 :type double-float) (uz 0d0 :type double-float)
  (radius 0d0 :type double-float) (best 0d0 :type double-float)
  (kind 0 :type fixnum) (handle -1 :type fixnum) (box -1 :type fixnum)
  (cx 0 :type fixnum) (cy 0 :type fixnum) (cz 0 :type fixnum)
  (nx 0d0 :type double-float) (ny 0d0 :type double-float) (nz 0d0 :type double-float)
  (ct 0d0 :type double-float)
  (cnx 0d0 :type double-float) (cny 0d0 :type double-float) (cnz 0d0 :type double-float)
  (exclude nil) (filter nil) (owners #() :type simple-vector))

(defmacro with-search ((&rest slots) search &body body)
  "Run BODY with each of SLOTS (names of query-search slots) bound as a symbol macro to that slot
of SEARCH. #C4STRY"
  (let ((s (gensym "SEARCH")))
    `(let ((,s ,search))
       (declare (type query-search ,s) (ignorable ,s))
       (symbol-macrolet ,(loop for slot in slots
                               collect `(,slot (,(intern (format nil "QUERY-SEARCH-~A" slot) '#:luv-physics) ,s)))
         ,@body))))

(declaim (inline candidate))

(defun candidate (s tt nx ny nz)
  "Make distance TT and normal NX NY NZ the candidate of S; return T. #C4STRY"
  (declare (type query-search s) (type double-float tt nx ny nz))
  (setf (query-search-ct s) tt (query-search-cnx s) nx (query-search-cny s) ny (query-search-cnz s) nz)
  t)

(defun offer (s kind what)
  "Make S's candidate its nearest hit, of KIND (a code) and WHAT (the handle or box row; for a cell
unused), if it is nearer than the nearest so far and the filter keeps it. Return true if it did. #C4STRY"
  (declare (type query-search s) (type fixnum kind what))
  (with-search (ct best filter) s
    (when (and (< ct best)
               (or (null filter)
                   (funcall (the function filter) (svref +hit-kinds+ kind)
                            (cond ((= kind +hit-body+) what)
                                  ((= kind +hit-box+) (svref (query-search-owners s) what))
                                  (t nil)))))
      (setf best ct
            (query-search-kind s) kind
            (query-search-nx s) (query-search-cnx s) (query-search-ny s) (query-search-cny s)
            (query-search-nz s) (query-search-cnz s))
      (if (= kind +hit-body+) (setf (query-search-handle s) what) (setf (query-search-box s) what))
      t)))

(declaim (inline sweep-sphere))

(defun sweep-sphere (s cx cy cz rr)
  "True when cast S meets the sphere of radius RR (the body's radius plus the cast's) about CX CY
CZ nearer than its nearest hit so far; its distance and outward normal are then S's candidate. A
cast that starts overlapping the sphere meets it at 0 when it heads deeper, else passes it. #C4STRY"
  (declare (type query-search s) (type double-float cx cy cz rr) #.+kernel-policy+)
  (with-search (ox oy oz ux uy uz best) s
    (let* ((mx (- ox cx)) (my (- oy cy)) (mz (- oz cz))
           (b (+ (* mx ux) (* my uy) (* mz uz)))
           (m2 (+ (* mx mx) (* my my) (* mz mz)))
           (r2 (* rr rr)))
      (cond ((< m2 r2)
             (cond ((= m2 0d0) (candidate s 0d0 (- ux) (- uy) (- uz)))
                   ((< b 0d0) (let ((d (dsqrt m2))) (candidate s 0d0 (/ mx d) (/ my d) (/ mz d))))
                   (t nil)))
            ((>= b 0d0) nil)
            (t
             ;; the offset of the centre from the line, found directly, not as b^2 - c
             (let* ((px (- mx (* b ux))) (py (- my (* b uy))) (pz (- mz (* b uz)))
                    (h2 (- r2 (+ (* px px) (* py py) (* pz pz)))))
               (when (>= h2 0d0)
                 (let ((tt (- (- b) (dsqrt h2))))
                   (when (< tt best)
                     (let ((inv (/ 1d0 rr)))
                       (candidate s tt (* inv (+ mx (* tt ux))) (* inv (+ my (* tt uy)))
                                  (* inv (+ mz (* tt uz))))))))))))))
;; Casts: a search, its hits and the shapes it meets:2 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:3]]
(declaim (inline sweep-rounded-box))

(defmacro push-out-face (bit d fx fy fz)
  "Take the exposed face BIT at depth D, outward normal FX FY FZ, as the nearest so far (DEPTH,
NX NY NZ). #C4STRY"
  `(when (and (logbitp ,bit exposed) (< ,d depth))
     (setf depth ,d nx ,fx ny ,fy nz ,fz)))

(defmacro rounded-face-hit (bit o u plane sign (o1 u1 lo1 hi1) (o2 u2 lo2 hi2) nx ny nz)
  "The hit of the search with the face BIT of the box (O the cast's origin and U its direction
along the face's axis, PLANE the face moved out by its radius, SIGN its side), approached from
outside and met within the face's span along its two other axes; noted in BT, BNX BNY BNZ and
FOUND. #C4STRY"
  ;; the plane of the face moved out by r, approached from outside
  `(when (and (logbitp ,bit exposed) (,(if (minusp sign) '> '<) ,u 0d0)
              (,(if (minusp sign) '<= '>=) ,o ,plane))
     (let ((tt (/ (- ,plane ,o) ,u)))
       (when (< tt bt)
         (let ((a (+ ,o1 (* tt ,u1))) (b (+ ,o2 (* tt ,u2))))
           (when (and (<= ,lo1 a ,hi1) (<= ,lo2 b ,hi2))
             (setf bt tt bnx ,nx bny ,ny bnz ,nz found t)))))))

(defmacro rounded-edge-hit (bit1 bit2 (oa ua ea sa) (ob ub eb sb) (oc uc lo hi) nxf nyf nzf)
  "The hit of the search with the quarter cylinder of radius R about the edge between the exposed
faces BIT1 and BIT2, entered from outside; noted in BT, BNX BNY BNZ and FOUND. #C4STRY"
  ;; the quarter cylinder of radius r about an edge, entered from outside
  `(when (and (logbitp ,bit1 exposed) (logbitp ,bit2 exposed))
     (let* ((pa (- ,oa ,ea)) (pb (- ,ob ,eb))
            (aa (+ (* ,ua ,ua) (* ,ub ,ub)))
            (bb (+ (* pa ,ua) (* pb ,ub)))
            (cc (- (+ (* pa pa) (* pb pb)) (* r r))))
       (when (and (> aa 0d0) (< bb 0d0) (>= cc 0d0))
         (let ((disc (- (* bb bb) (* aa cc))))
           (when (>= disc 0d0)
             (let ((tt (/ (- (- bb) (dsqrt disc)) aa)))
               (when (< tt bt)
                 (let ((qa (+ pa (* tt ,ua))) (qb (+ pb (* tt ,ub)))
                       (c (+ ,oc (* tt ,uc))))
                   (when (and (>= (* qa ,sa) 0d0) (>= (* qb ,sb) 0d0) (<= ,lo c ,hi))
                     (let ((inv (/ 1d0 r)))
                       (setf bt tt bnx ,nxf bny ,nyf bnz ,nzf found t))))))))))))

(defmacro rounded-corner-hit (bx by bz cx cy cz sx sy sz)
  "The hit of the search with the eighth of a sphere of radius R about the corner of the exposed
faces BX, BY and BZ, entered from outside; noted in BT, BNX BNY BNZ and FOUND. #C4STRY"
  ;; the eighth of a sphere of radius r about a corner, entered from outside
  `(when (and (logbitp ,bx exposed) (logbitp ,by exposed) (logbitp ,bz exposed))
     (let* ((mx (- ox ,cx)) (my (- oy ,cy)) (mz (- oz ,cz))
            (b (+ (* mx ux) (* my uy) (* mz uz))))
       (when (< b 0d0)
         (let* ((qx (- mx (* b ux))) (qy (- my (* b uy))) (qz (- mz (* b uz)))
                (h2 (- (* r r) (+ (* qx qx) (* qy qy) (* qz qz)))))
           (when (>= h2 0d0)
             (let ((tt (- (- b) (dsqrt h2))))
               (when (< tt bt)
                 (let ((hx (+ mx (* tt ux))) (hy (+ my (* tt uy))) (hz (+ mz (* tt uz))))
                   (when (and (>= (* hx ,sx) 0d0) (>= (* hy ,sy) 0d0) (>= (* hz ,sz) 0d0))
                     (let ((inv (/ 1d0 r)))
                       (setf bt tt bnx (* hx inv) bny (* hy inv) bnz (* hz inv)
                             found t))))))))))))
;; Casts: a search, its hits and the shapes it meets:3 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:4]]
(defmacro rounded-edge-hits ()
  "The twelve edges of the box, each a rounded-edge-hit. #C4STRY"
  `(progn
     ,@(loop for (sx bx ex) in '((-1d0 0 x0) (1d0 1 x1))
             append (loop for (sy by ey) in '((-1d0 2 y0) (1d0 3 y1))
                          collect `(rounded-edge-hit ,bx ,by (ox ux ,ex ,sx) (oy uy ,ey ,sy) (oz uz z0 z1)
                                         (* qa inv) (* qb inv) 0d0)))
     ,@(loop for (sx bx ex) in '((-1d0 0 x0) (1d0 1 x1))
             append (loop for (sz bz ez) in '((-1d0 4 z0) (1d0 5 z1))
                          collect `(rounded-edge-hit ,bx ,bz (ox ux ,ex ,sx) (oz uz ,ez ,sz) (oy uy y0 y1)
                                         (* qa inv) 0d0 (* qb inv))))
     ,@(loop for (sy by ey) in '((-1d0 2 y0) (1d0 3 y1))
             append (loop for (sz bz ez) in '((-1d0 4 z0) (1d0 5 z1))
                          collect `(rounded-edge-hit ,by ,bz (oy uy ,ey ,sy) (oz uz ,ez ,sz) (ox ux x0 x1)
                                         0d0 (* qa inv) (* qb inv))))))

(defmacro rounded-corner-hits ()
  "The eight corners of the box, each a rounded-corner-hit. #C4STRY"
  `(progn
     ,@(loop for (sx bx ex) in '((-1d0 0 x0) (1d0 1 x1))
             append (loop for (sy by ey) in '((-1d0 2 y0) (1d0 3 y1))
                          append (loop for (sz bz ez) in '((-1d0 4 z0) (1d0 5 z1))
                                       collect `(rounded-corner-hit ,bx ,by ,bz ,ex ,ey ,ez ,sx ,sy ,sz))))))

(defun sweep-rounded-box (s x0 y0 z0 x1 y1 z1 exposed)
  "True when cast S meets the box X0..X1 Y0..Y1 Z0..Z1 grown by its radius nearer than its nearest
hit so far, through a face whose bit is set in EXPOSED (bits 0-5: -x +x -y +y -z +z), an edge both
of whose faces are exposed, or a corner all three of whose faces are; the distance and the outward
normal are then S's candidate. A cast starting in or on the box, or within its radius of it,
meets it at 0 when it heads deeper along the push-out normal of the nearest exposed feature, else
passes it; inside a box with no exposed face, it meets it at 0 with the normal against the
cast. #C4STRY"
  (declare (type query-search s) (type double-float x0 y0 z0 x1 y1 z1) (type (unsigned-byte 6) exposed)
           #.+kernel-policy+)
  (with-search (ox oy oz ux uy uz radius best) s
    (let* ((r radius)
           (px (max x0 (min x1 ox))) (py (max y0 (min y1 oy))) (pz (max z0 (min z1 oz)))
           (dx (- ox px)) (dy (- oy py)) (dz (- oz pz))
           (d2 (+ (* dx dx) (* dy dy) (* dz dz))))
      (cond
        ((= d2 0d0)
         ;; in the closed box: pushed out through the nearest exposed face
         (let ((depth most-positive-double-float) (nx 0d0) (ny 0d0) (nz 0d0))
           (declare (type double-float depth nx ny nz))
           (push-out-face 0 (- ox x0) -1d0 0d0 0d0) (push-out-face 1 (- x1 ox) 1d0 0d0 0d0)
           (push-out-face 2 (- oy y0) 0d0 -1d0 0d0) (push-out-face 3 (- y1 oy) 0d0 1d0 0d0)
           (push-out-face 4 (- oz z0) 0d0 0d0 -1d0) (push-out-face 5 (- z1 oz) 0d0 0d0 1d0)
           (cond ((= depth most-positive-double-float) (candidate s 0d0 (- ux) (- uy) (- uz)))
                 ((< (+ (* ux nx) (* uy ny) (* uz nz)) 0d0) (candidate s 0d0 nx ny nz))
                 (t nil))))
        ((< d2 (* r r))
         ;; overlapping: the nearest feature must be exposed and the cast head deeper
         (let* ((d (dsqrt d2)) (nx (/ dx d)) (ny (/ dy d)) (nz (/ dz d)))
           (and (or (>= ox x0) (logbitp 0 exposed)) (or (<= ox x1) (logbitp 1 exposed))
                (or (>= oy y0) (logbitp 2 exposed)) (or (<= oy y1) (logbitp 3 exposed))
                (or (>= oz z0) (logbitp 4 exposed)) (or (<= oz z1) (logbitp 5 exposed))
                (< (+ (* ux nx) (* uy ny) (* uz nz)) 0d0)
                (candidate s 0d0 nx ny nz))))
        (t
         (let ((bt best) (bnx 0d0) (bny 0d0) (bnz 0d0) (found nil))
           (declare (type double-float bt bnx bny bnz))
           (rounded-face-hit 0 ox ux (- x0 r) -1 (oy uy y0 y1) (oz uz z0 z1) -1d0 0d0 0d0)
           (rounded-face-hit 1 ox ux (+ x1 r) 1 (oy uy y0 y1) (oz uz z0 z1) 1d0 0d0 0d0)
           (rounded-face-hit 2 oy uy (- y0 r) -1 (ox ux x0 x1) (oz uz z0 z1) 0d0 -1d0 0d0)
           (rounded-face-hit 3 oy uy (+ y1 r) 1 (ox ux x0 x1) (oz uz z0 z1) 0d0 1d0 0d0)
           (rounded-face-hit 4 oz uz (- z0 r) -1 (ox ux x0 x1) (oy uy y0 y1) 0d0 0d0 -1d0)
           (rounded-face-hit 5 oz uz (+ z1 r) 1 (ox ux x0 x1) (oy uy y0 y1) 0d0 0d0 1d0)
           (when (> r 0d0)
             (rounded-edge-hits)
             (rounded-corner-hits))
           (when found (candidate s bt bnx bny bnz))))))))

(defun sweep-boxes (s world)
  "Sweep cast S against every box posted for the step (all faces exposed), skipping a box whose
owner is the excluded one. #C4STRY"
  (declare (type query-search s))
  (let ((boxes (physics-world-boxes world)) (exclude (query-search-exclude s))
        (owners (physics-world-box-owners world)))
    (with-box-columns (min-x min-y min-z max-x max-y max-z) boxes
      (dotimes (b (box-columns-length boxes))
        (unless (and exclude (eql exclude (svref owners b)))
          (when (sweep-rounded-box s (float (aref min-x b) 1d0) (float (aref min-y b) 1d0) (float (aref min-z b) 1d0)
                                   (float (aref max-x b) 1d0) (float (aref max-y b) 1d0) (float (aref max-z b) 1d0)
                                   63)
            (offer s +hit-box+ b))))))
  s)
;; Casts: a search, its hits and the shapes it meets:4 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:5]]
(declaim (inline segment-box-range))

(defun segment-box-range (s x0 y0 z0 x1 y1 z1 t-max)
  "The part [T-IN, T-OUT] of cast S's path from 0 to T-MAX inside the box X0..X1 Y0..Y1 Z0..Z1, as two
values; T-IN > T-OUT when it misses. #C4STRY"
  (declare (type query-search s) (type double-float x0 y0 z0 x1 y1 z1 t-max))
  (let ((lo 0d0) (hi t-max))
    (declare (type double-float lo hi))
    (macrolet ((slab (o u a b)
                 `(let ((o (,o s)) (u (,u s)))
                    (if (= u 0d0)
                        (unless (<= ,a o ,b) (setf lo 1d0 hi 0d0))
                        (let* ((inv (/ 1d0 u)) (ta (* (- ,a o) inv)) (tb (* (- ,b o) inv)))
                          (setf lo (max lo (min ta tb)) hi (min hi (max ta tb))))))))
      (slab query-search-ox query-search-ux x0 x1)
      (slab query-search-oy query-search-uy y0 y1)
      (slab query-search-oz query-search-uz z0 z1))
    (values lo hi)))

(defconstant +path-part-cells+ 1.5d0
  "How many cells' length of path a walk of the bodies takes at a time. #C4STRY")

(declaim (inline path-walk-range path-part-layers path-layer-piece path-piece-cells))

(defun path-walk-range (s grid rho)
  "The part [LO, HI] of cast S's path, up to its nearest hit so far, that a walk of GRID's
cells within RHO (a double) of the path must cover, as two values: a dense grid cuts the path
to its own box grown by RHO; a hashed grid has no box, and the whole path is walked. #C4STRY"
  (declare (type query-search s) (type hash-grid grid) (type double-float rho))
  (if (hash-grid-dense grid)
      (let ((c (/ 1d0 (float (hash-grid-inv-cell grid) 1d0)))
            (ox (hash-grid-ox grid)) (oy (hash-grid-oy grid)) (oz (hash-grid-oz grid)))
        (segment-box-range s (- (* c ox) rho) (- (* c oy) rho) (- (* c oz) rho)
                           (+ (* c (+ ox (hash-grid-nx grid))) rho) (+ (* c (+ oy (hash-grid-ny grid))) rho)
                           (+ (* c (+ oz (hash-grid-nz grid))) rho)
                           (query-search-best s)))
      (values 0d0 (query-search-best s))))

(defun path-part-layers (s grid t0 t1 rho inv)
  "The layers of cells along z, K0 to K1 as two values, within RHO of the part [T0, T1] of cast
S's path, for cells INV to the metre; a dense grid's layers are cut to its box. #C4STRY"
  (declare (type query-search s) (type hash-grid grid) (type double-float t0 t1 rho inv))
  (let* ((oz (query-search-oz s)) (uz (query-search-uz s))
         (az (+ oz (* t0 uz))) (bz (+ oz (* t1 uz)))
         (k0 (dcell (* (- (min az bz) rho) inv))) (k1 (dcell (* (+ (max az bz) rho) inv))))
    (declare (type fixnum k0 k1))
    (if (hash-grid-dense grid)
        (values (max k0 (hash-grid-oz grid)) (min k1 (+ (hash-grid-oz grid) (hash-grid-nz grid) -1)))
        (values k0 k1))))

(defun path-layer-piece (s k c rho ta tb)
  "The piece of the part [TA, TB] of cast S's path within RHO of layer K of cells C metres high,
as two values; the first exceeds the second when there is none. #C4STRY"
  (declare (type query-search s) (type fixnum k) (type double-float c rho ta tb))
  (let ((oz (query-search-oz s)) (uz (query-search-uz s)))
    (if (= uz 0d0)
        (values ta tb)
        (let* ((iuz (/ 1d0 uz))
               (za (* (- (- (* c k) rho) oz) iuz)) (zb (* (- (+ (* c (1+ k)) rho) oz) iuz)))
          (values (max ta (min za zb)) (min tb (max za zb)))))))

(defun path-piece-cells (s ta tb rho inv)
  "The cells along x, I0 to I1, and along y, J0 to J1, within RHO of the piece [TA, TB] of cast
S's path, for cells INV to the metre, as four values. #C4STRY"
  (declare (type query-search s) (type double-float ta tb rho inv))
  (let ((ya (+ (query-search-oy s) (* ta (query-search-uy s)))) (yb (+ (query-search-oy s) (* tb (query-search-uy s))))
        (xa (+ (query-search-ox s) (* ta (query-search-ux s)))) (xb (+ (query-search-ox s) (* tb (query-search-ux s)))))
    (values (dcell (* (- (min xa xb) rho) inv)) (dcell (* (+ (max xa xb) rho) inv))
            (dcell (* (- (min ya yb) rho) inv)) (dcell (* (+ (max ya yb) rho) inv)))))

(defmacro do-path-entries ((entry) (s grid rho) &body body)
  "For cast S, run BODY with ENTRY bound to the place, in GRID's order, of each item of GRID whose
cell lies within RHO (a double: the farthest a centre can be from the path and still be met, per
axis) of the path from 0 to the nearest hit so far, +path-part-cells+ cells' length of path at a
time, until the nearest hit is no farther than the part walked. For each layer of cells along z,
the part is cut to the piece within RHO of the layer (path-layer-piece), and the cells visited
are those within RHO of that piece (path-piece-cells), in do-grid-entries' order. #C4STRY"
  (let ((q (gensym "S")) (g (gensym "G")) (r (gensym "RHO")) (inv (gensym "INV")) (c (gensym "C"))
        (visit (gensym "VISIT")) (lo (gensym "LO")) (hi (gensym "HI")) (t0 (gensym "T0")) (t1 (gensym "T1"))
        (k (gensym "K")) (k0 (gensym "K0")) (k1 (gensym "K1")) (ta (gensym "TA")) (tb (gensym "TB"))
        (i0 (gensym "I0")) (i1 (gensym "I1")) (j0 (gensym "J0")) (j1 (gensym "J1")) (e (gensym "E")))
    `(let ((,q ,s) (,g ,grid) (,r ,rho))
       (declare (type query-search ,q) (type hash-grid ,g) (type double-float ,r))
       (flet ((,visit (,entry) (declare (type index ,entry)) ,@body))
         (declare (inline ,visit))
         (unless (zerop (hash-grid-count ,g))
           (let* ((,inv (float (hash-grid-inv-cell ,g) 1d0)) (,c (/ 1d0 ,inv)))
             (declare (type double-float ,inv ,c))
             (multiple-value-bind (,lo ,hi) (path-walk-range ,q ,g ,r)
               (declare (type double-float ,lo ,hi))
               (loop with ,t0 of-type double-float = ,lo
                     while (and (<= ,t0 ,hi) (< ,t0 (query-search-best ,q)))
                     do (let ((,t1 (min (query-search-best ,q) ,hi (+ ,t0 (* +path-part-cells+ ,c)))))
                          (declare (type double-float ,t1))
                          (multiple-value-bind (,k0 ,k1) (path-part-layers ,q ,g ,t0 ,t1 ,r ,inv)
                            (loop for ,k of-type fixnum from ,k0 to ,k1 do
                              (multiple-value-bind (,ta ,tb)
                                  (path-layer-piece ,q ,k ,c ,r ,t0 (min ,t1 (query-search-best ,q)))
                                (when (<= ,ta ,tb)
                                  (multiple-value-bind (,i0 ,i1 ,j0 ,j1) (path-piece-cells ,q ,ta ,tb ,r ,inv)
                                    (do-grid-entries (,e ,g) (,i0 ,j0 ,k ,i1 ,j1 ,k) (,visit ,e)))))))
                          (when (or (<= (query-search-best ,q) ,t1) (>= ,t1 ,hi)) (return))
                          (setf ,t0 ,t1))))))))))
;; Casts: a search, its hits and the shapes it meets:5 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:6]]
(defun sweep-awake (s view world)
  "Sweep cast S against the awake bodies of VIEW, through its own grid, each entry tested from the
grid's columns of centre, radius and handle; the excluded body is passed over. #C4STRY"
  (declare (type query-search s) (type query-view view) #.+kernel-policy+)
  (let* ((exclude (query-search-exclude s)) (radius (query-search-radius s))
         (rho (+ (float (the single-float (physics-world-max-radius world)) 1d0) radius 1d-4))
         (g (query-view-awake-grid view)) (gx (hash-grid-xs g)) (gy (hash-grid-ys g)) (gz (hash-grid-zs g))
         (radii (query-view-awake-radii view)) (handles (query-view-awake-handles view))
         (boxes (physics-world-box-bodies world)))
    (declare (type double-float radius rho) (type f32-column gx gy gz radii) (type fixnum-column handles))
    (do-path-entries (e) (s g rho)
      (when (if (and boxes (box-entry-p boxes (aref handles e)))
                ;; a box is met on its faces ([[#C4STBX]])
                (sweep-body-box s world (aref handles e))
                (sweep-sphere s (float (aref gx e) 1d0) (float (aref gy e) 1d0) (float (aref gz e) 1d0)
                              (+ (float (aref radii e) 1d0) radius)))
        (let ((h (aref handles e)))
          (unless (eql h exclude) (offer s +hit-body+ h))))))
  s)

(declaim (inline centre-near-path-p))

(defun centre-near-path-p (s x y z rho)
  "Whether a centre at X Y Z (doubles) may be met by cast S: it is not farther than RHO from the
path's line, nor wholly behind the cast, nor wholly beyond its nearest hit so far. #C4STRY"
  (declare (type query-search s) (type double-float x y z rho))
  (let* ((mx (- x (query-search-ox s))) (my (- y (query-search-oy s))) (mz (- z (query-search-oz s)))
         (along (+ (* mx (query-search-ux s)) (* my (query-search-uy s)) (* mz (query-search-uz s)))))
    (and (> along (- rho)) (< (- along rho) (query-search-best s))
         (<= (- (+ (* mx mx) (* my my) (* mz mz)) (* along along)) (* rho rho)))))

(defun sweep-sleepers (s view world)
  "Sweep cast S against the sleepers of VIEW: through its sleeping grid, each entry first judged by
the grid's copy of its centre and then found through the handle table; then the sleeping strays,
one by one or through their grid. The excluded body is passed over. #C4STRY"
  (declare (type query-search s) (type query-view view) #.+kernel-policy+)
  (let* ((exclude (query-search-exclude s)) (radius (query-search-radius s))
         (rho (+ (float (the single-float (physics-world-max-radius world)) 1d0) radius 1d-4))
         (boxes (physics-world-box-bodies world)))
    (declare (type double-float radius rho))
    (with-body-columns ((cx x) (cy y) (cz z) (cr radius) (ch handle)) (physics-world-sleeping world)
      (flet ((try (row)
               (declare (type index row))
               (when (if (and boxes (box-entry-p boxes (aref ch row)))
                         ;; a box is met on its faces ([[#C4STBX]])
                         (sweep-body-box s world (aref ch row))
                         (sweep-sphere s (float (aref cx row) 1d0) (float (aref cy row) 1d0) (float (aref cz row) 1d0)
                                       (+ (float (aref cr row) 1d0) radius)))
                 (let ((h (aref ch row)))
                   (unless (eql h exclude) (offer s +hit-body+ h))))))
        (declare (inline try))
        (macrolet ((walk (grid direct)
                     ;; an item is first judged by the grid's copy of its centre, in one run of
                     ;; memory with its neighbours': passed over when farther from the path's line
                     ;; than RHO, or wholly behind the cast or beyond its nearest hit
                     `(let* ((g ,grid) (gx (hash-grid-xs g)) (gy (hash-grid-ys g)) (gz (hash-grid-zs g))
                             (items (hash-grid-items g)))
                        (declare (type f32-column gx gy gz) (type fixnum-column items))
                        (do-path-entries (e) (s g rho)
                          (when (centre-near-path-p s (float (aref gx e) 1d0) (float (aref gy e) 1d0)
                                                    (float (aref gz e) 1d0) rho)
                            (let ((row ,(if direct `(aref items e) `(view-row view world t (aref items e)))))
                              (declare (type fixnum row))
                              (when (>= row 0) (try row))))))))
          (walk (query-view-sleeping-grid view) nil)
          (if (plusp (hash-grid-count (query-view-sleeping-stray-grid view)))
              (walk (query-view-sleeping-stray-grid view) t)
              (let ((rows (query-view-sleeping-strays view)))
                (declare (type fixnum-column rows))
                (dotimes (q (query-view-sleeping-stray-count view))
                  (try (aref rows q)))))))))
  s)

(defun sweep-bodies (s view world)
  "Sweep cast S against the bodies of VIEW, the awake ones and then the sleepers. #C4STRY"
  (sweep-awake s view world)
  (sweep-sleepers s view world))
;; Casts: a search, its hits and the shapes it meets:6 ends here

;; [[file:../physics.org::#C4STRY][Casts: a search, its hits and the shapes it meets:7]]
(declaim (inline cast-argument))

(defun cast-argument (world name value)
  "VALUE as a double-float, after checking it is finite (invalid-physics-number naming NAME). A
single float, the common case, is tested by its exponent bits, which is what finite-f32 decides
through generic arithmetic. #C4STRY"
  (if (and (typep value 'single-float)
           (/= 255 (ldb (byte 8 23) (sb-kernel:single-float-bits value))))
      (float value 1d0)
      (float (finite-f32 name value world) 1d0)))

(declaim (inline cast-coordinate))

(defun cast-coordinate (world name value)
  "VALUE as a double-float, after checking it is finite and within the coordinate limit. #C4STRY"
  (let ((v (cast-argument world name value)))
    (declare (type double-float v))
    (unless (< (abs v) (float +physics-coordinate-limit+ 1d0))
      (check-coordinate name (float v 1.0) world))
    v))

(defun physics-cast (operation world x y z radius dx dy dz max-distance bodies cells boxes exclude filter hit)
  "The cast of OPERATION: check every argument, then walk the boxes, the bodies and the cells in
turn, each up to the nearest hit so far. Fill HIT (or a fresh physics-hit) and return it, or
return NIL. #C4STRY"
  (let* ((x (cast-coordinate world :x x)) (y (cast-coordinate world :y y)) (z (cast-coordinate world :z z))
         (ddx (cast-argument world :dx dx)) (ddy (cast-argument world :dy dy)) (ddz (cast-argument world :dz dz))
         (r (cast-argument world :radius radius))
         (limit (cast-argument world :max-distance max-distance))
         (length (dsqrt (+ (* ddx ddx) (* ddy ddy) (* ddz ddz)))))
    (declare (type double-float x y z ddx ddy ddz r limit length))
    (when (= length 0d0)
      (error 'invalid-physics-parameter :world world :name :direction :value (list dx dy dz)
                                        :expected "a direction of non-zero length"))
    (unless (<= 0d0 limit (float +physics-coordinate-limit+ 1d0))
      (error 'invalid-physics-parameter :world world :name :max-distance :value max-distance
                                        :expected (format nil "from 0 to ~D m" +physics-coordinate-limit+)))
    (unless (or (eq operation 'physics-ray-cast) (< 0d0 r 8.000001d0))
      (error 'invalid-physics-parameter :world world :name :radius :value radius :expected "in (0, 8] m"))
    (unless (or (null filter) (functionp filter))
      (error 'invalid-physics-parameter :world world :name :filter :value filter
                                        :expected "a function of a kind and a handle or owner, or NIL"))
    (unless (or (null hit) (physics-hit-p hit))
      (error 'invalid-physics-parameter :world world :name :hit :value hit :expected "a physics-hit or NIL"))
    (let* ((view (world-query-view world))
           (nested (query-view-busy view))
           (s (if (or nested (null (query-view-search view)))
                  (let ((fresh (make-query-search)))
                    (unless nested (setf (query-view-search view) fresh))
                    fresh)
                  (query-view-search view))))
      (declare (type query-search s))
      (setf (query-search-ox s) x (query-search-oy s) y (query-search-oz s) z
            (query-search-ux s) (/ ddx length) (query-search-uy s) (/ ddy length) (query-search-uz s) (/ ddz length)
            (query-search-radius s) r (query-search-best s) limit (query-search-kind s) 0
            (query-search-handle s) -1 (query-search-box s) -1
            (query-search-exclude s) exclude (query-search-filter s) filter
            (query-search-owners s) (physics-world-box-owners world))
      (flet ((walk ()
               (when boxes (sweep-boxes s world))
               (when bodies (sweep-bodies s view world))
               (when (and cells (physics-world-terrain world))
                 (if (eq operation 'physics-ray-cast)
                     (ray-cells s (query-view-probe view))
                     (sweep-cells s (query-view-probe view))))))
        (unwind-protect
             (progn (setf (query-view-busy view) t)
                    (if filter (with-world-held (world) (walk)) (walk)))
          (unless nested (setf (query-view-busy view) nil))))
      (let ((kind (query-search-kind s)))
        (declare (type fixnum kind))
        (unless (zerop kind)
          ;; the numbers are read back from the search: a double live across the
          ;; unwind-protect above would be boxed
          (let ((hit (or hit (make-physics-hit)))
                (tt (query-search-best s)) (nx (query-search-nx s)) (ny (query-search-ny s)) (nz (query-search-nz s))
                (x (query-search-ox s)) (y (query-search-oy s)) (z (query-search-oz s)) (r (query-search-radius s)))
            (declare (type double-float tt nx ny nz x y z r))
            (setf (physics-hit-kind hit) (svref +hit-kinds+ kind)
                  (physics-hit-handle hit) (if (= kind +hit-body+) (query-search-handle s) -1)
                  (physics-hit-owner hit) (if (= kind +hit-box+) (svref (query-search-owners s) (query-search-box s)) nil)
                  (physics-hit-cell-x hit) (if (= kind +hit-cell+) (query-search-cx s) 0)
                  (physics-hit-cell-y hit) (if (= kind +hit-cell+) (query-search-cy s) 0)
                  (physics-hit-cell-z hit) (if (= kind +hit-cell+) (query-search-cz s) 0)
                  (physics-hit-x hit) (coerce (- (+ x (* tt (query-search-ux s))) (* r nx)) 'single-float)
                  (physics-hit-y hit) (coerce (- (+ y (* tt (query-search-uy s))) (* r ny)) 'single-float)
                  (physics-hit-z hit) (coerce (- (+ z (* tt (query-search-uz s))) (* r nz)) 'single-float)
                  (physics-hit-nx hit) (coerce nx 'single-float) (physics-hit-ny hit) (coerce ny 'single-float)
                  (physics-hit-nz hit) (coerce nz 'single-float) (physics-hit-distance hit) (coerce tt 'single-float))
            hit))))))
;; Casts: a search, its hits and the shapes it meets:7 ends here

;; [[file:../physics.org::#C4STBX][A cast meets a box body on its faces:1]]
(defun box-entry-p (boxes handle)
  "True when BOXES, a world's box set or NIL, holds extents for the slot of HANDLE: the body is a
box. #C4STBX"
  (declare (type fixnum handle))
  (and boxes
       (let ((slot (handle-index handle)) (hx (box-set-hx boxes)))
         (and (< slot (length hx)) (> (aref hx slot) 0.0)))))

(defun sweep-body-box (s world handle)
  "True when cast S meets the box body HANDLE of WORLD nearer than its nearest hit so far: the box
of its half-extents about its centre, turned by its orientation, grown by the cast's radius; the
distance and the outward normal are then S's candidate. #C4STBX"
  (declare (type query-search s) (type fixnum handle))
  (multiple-value-bind (set row) (resolve-handle world handle)
    (let* ((buffer (set-buffer world set)) (boxes (physics-world-box-bodies world))
           (slot (handle-index handle))
           (hx (float (aref (box-set-hx boxes) slot) 1d0)) (hy (float (aref (box-set-hy boxes) slot) 1d0))
           (hz (float (aref (box-set-hz boxes) slot) 1d0)))
      (declare (type double-float hx hy hz))
      (with-body-columns (x y z qw qx qy qz) buffer
        (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33)
            (box-axes (aref qw row) (aref qx row) (aref qy row) (aref qz row))
          (let ((r11 (float r11 1d0)) (r12 (float r12 1d0)) (r13 (float r13 1d0))
                (r21 (float r21 1d0)) (r22 (float r22 1d0)) (r23 (float r23 1d0))
                (r31 (float r31 1d0)) (r32 (float r32 1d0)) (r33 (float r33 1d0)))
            (declare (type double-float r11 r12 r13 r21 r22 r23 r31 r32 r33))
            (with-search (ox oy oz ux uy uz cnx cny cnz) s
              (let ((wox ox) (woy oy) (woz oz) (wux ux) (wuy uy) (wuz uz)
                    (mx (- ox (float (aref x row) 1d0))) (my (- oy (float (aref y row) 1d0)))
                    (mz (- oz (float (aref z row) 1d0))))
                (declare (type double-float wox woy woz wux wuy wuz mx my mz))
                ;; the cast in the box's frame: R^T (o - c) and R^T u
                (setf ox (+ (* r11 mx) (* r21 my) (* r31 mz)) oy (+ (* r12 mx) (* r22 my) (* r32 mz))
                      oz (+ (* r13 mx) (* r23 my) (* r33 mz))
                      ux (+ (* r11 wux) (* r21 wuy) (* r31 wuz)) uy (+ (* r12 wux) (* r22 wuy) (* r32 wuz))
                      uz (+ (* r13 wux) (* r23 wuy) (* r33 wuz)))
                (let ((met (sweep-rounded-box s (- hx) (- hy) (- hz) hx hy hz 63)))
                  (setf ox wox oy woy oz woz ux wux uy wuy uz wuz)
                  (when met
                    ;; the normal back in the world: R n
                    (let ((nx cnx) (ny cny) (nz cnz))
                      (declare (type double-float nx ny nz))
                      (setf cnx (+ (* r11 nx) (* r12 ny) (* r13 nz)) cny (+ (* r21 nx) (* r22 ny) (* r23 nz))
                            cnz (+ (* r31 nx) (* r32 ny) (* r33 nz)))))
                  met)))))))))
;; A cast meets a box body on its faces:1 ends here

;; [[file:../physics.org::#R4YC57][Rays walk the cells in order:1]]
(defun ray-cells (s probe)
  "Walk the cells cast S passes through, in order (Amanatides and Woo's traversal), up to its
nearest hit so far, and make the first solid one the filter keeps its nearest hit: the cell it
starts in at 0 with the normal against the cast, or one it enters at the distance it crosses
into it, with the normal of the face crossed. Where the ray leaves a cell through an edge or a
corner, every cell that meets that edge or corner is tried, fewest steps first. #R4YC57"
  (declare (type query-search s) (type terrain-probe probe) #.+kernel-policy+)
  (with-search (ox oy oz ux uy uz best cx cy cz) s
    (with-chunk-reader (solid-p probe)
      ;; the cell the ray is in, its step along each axis, the distance to the next face
      ;; crossed along each axis, and the distance between faces along each
      (let* ((ix (dcell ox)) (iy (dcell oy)) (iz (dcell oz))
             (sx (cond ((> ux 0d0) 1) ((< ux 0d0) -1) (t 0)))
             (sy (cond ((> uy 0d0) 1) ((< uy 0d0) -1) (t 0)))
             (sz (cond ((> uz 0d0) 1) ((< uz 0d0) -1) (t 0)))
             (huge 1d300)
             (tx (if (= sx 0) huge (/ (- (float (if (> sx 0) (1+ ix) ix) 1d0) ox) ux)))
             (ty (if (= sy 0) huge (/ (- (float (if (> sy 0) (1+ iy) iy) 1d0) oy) uy)))
             (tz (if (= sz 0) huge (/ (- (float (if (> sz 0) (1+ iz) iz) 1d0) oz) uz)))
             (ddx (if (= sx 0) 0d0 (/ 1d0 (abs ux))))
             (ddy (if (= sy 0) 0d0 (/ 1d0 (abs uy))))
             (ddz (if (= sz 0) 0d0 (/ 1d0 (abs uz)))))
        (declare (type cell ix iy iz) (type fixnum sx sy sz) (type double-float tx ty tz ddx ddy ddz))
        (labels ((try (x y z tt axis)
                   (declare (type cell x y z) (type double-float tt) (type (integer 0 3) axis))
                   ;; axis 3: the cell the ray starts in
                   (when (and (solid-p x y z)
                              (case axis
                                (0 (candidate s tt (if (> ux 0d0) -1d0 1d0) 0d0 0d0))
                                (1 (candidate s tt 0d0 (if (> uy 0d0) -1d0 1d0) 0d0))
                                (2 (candidate s tt 0d0 0d0 (if (> uz 0d0) -1d0 1d0)))
                                (t (candidate s tt (- ux) (- uy) (- uz))))
                              (offer s +hit-cell+ 0))
                     (setf cx x cy y cz z)
                     t))
                 (cross (tn mx my mz)
                   ;; the cells entered at TN: through one face, or every cell meeting the
                   ;; edge or corner crossed, fewest steps first
                   (if (and (not (and mx my)) (not (and mx mz)) (not (and my mz)))
                       (cond (mx (try (+ ix sx) iy iz tn 0))
                             (my (try ix (+ iy sy) iz tn 1))
                             (t (try ix iy (+ iz sz) tn 2)))
                       (let ((ax (if mx sx 0)) (ay (if my sy 0)) (az (if mz sz 0)))
                         (or (and mx (try (+ ix ax) iy iz tn 0))
                             (and my (try ix (+ iy ay) iz tn 1))
                             (and mz (try ix iy (+ iz az) tn 2))
                             (and mx my (try (+ ix ax) (+ iy ay) iz tn 0))
                             (and mx mz (try (+ ix ax) iy (+ iz az) tn 0))
                             (and my mz (try ix (+ iy ay) (+ iz az) tn 1))
                             (and mx my mz (try (+ ix ax) (+ iy ay) (+ iz az) tn 0)))))))
          (declare (inline try cross))
          (unless (try ix iy iz 0d0 3)
            (loop
              (let ((tn (min tx ty tz)))
                (when (>= tn best) (return))
                (let ((mx (= tx tn)) (my (= ty tn)) (mz (= tz tn)))
                  (when (cross tn mx my mz) (return))
                  (when mx (setf ix (+ ix sx) tx (+ tx ddx)))
                  (when my (setf iy (+ iy sy) ty (+ ty ddy)))
                  (when mz (setf iz (+ iz sz) tz (+ tz ddz)))))))))))
  s)

(defun physics-ray-cast (world x y z dx dy dz max-distance &key (bodies t) (cells t) (boxes t) exclude filter hit)
  "The first thing the ray from X Y Z along DX DY DZ meets closer than MAX-DISTANCE: a body (awake
or asleep), a solid cell or a box posted for the step, as a physics-hit (HIT, filled, when given),
or NIL. BODIES, CELLS and BOXES choose the kinds; EXCLUDE, a handle or a box's owner, is passed
through; FILTER, a function of the kind (:body :cell :box) and the handle, NIL or owner, keeps a
hit when it returns true. #R4YC57"
  (check-world world 'physics-ray-cast)
  (physics-cast 'physics-ray-cast world x y z 0 dx dy dz max-distance bodies cells boxes exclude filter hit))
;; Rays walk the cells in order:1 ends here

;; [[file:../physics.org::#S9WEEP][Spheres swept along a path:1]]
(defmacro sweep-cell-if-solid (i j k)
  "When cell I J K is solid, sweep the cast's sphere against it (sweep-rounded-box), its faces
shared with air exposed, and take a nearer hit as the cast's. Expanded in sweep-cells, inside its
chunk reader (solid-p) and its search's names (s, cx, cy, cz). #S9WEEP"
  `(when (solid-p ,i ,j ,k)
     (let ((exposed (logior (if (solid-p (1- ,i) ,j ,k) 0 1) (if (solid-p (1+ ,i) ,j ,k) 0 2)
                            (if (solid-p ,i (1- ,j) ,k) 0 4) (if (solid-p ,i (1+ ,j) ,k) 0 8)
                            (if (solid-p ,i ,j (1- ,k)) 0 16) (if (solid-p ,i ,j (1+ ,k)) 0 32)))
           (x0 (float ,i 1d0)) (y0 (float ,j 1d0)) (z0 (float ,k 1d0)))
       (when (and (sweep-rounded-box s x0 y0 z0 (+ x0 1d0) (+ y0 1d0) (+ z0 1d0) exposed)
                  (offer s +hit-cell+ 0))
         (setf cx ,i cy ,j cz ,k)))))

(defun sweep-cells (s probe)
  "Find the first solid cell the sphere of cast S meets along its path, up to its nearest hit so
far: walking the path a metre at a time, every solid cell within the radius of that metre is
swept (sweep-rounded-box) with the faces it shares with air as its exposed faces; a cast whose
centre starts in a solid cell meets it at 0 with the normal against the cast. #S9WEEP"
  (declare (type query-search s) (type terrain-probe probe) #.+kernel-policy+)
  (with-search (ox oy oz ux uy uz radius best cx cy cz) s
    (with-chunk-reader (solid-p probe)
      (let ((ix (dcell ox)) (iy (dcell oy)) (iz (dcell oz)) (r radius))
        (declare (type cell ix iy iz))
        (if (solid-p ix iy iz)
            (when (and (candidate s 0d0 (- ux) (- uy) (- uz)) (offer s +hit-cell+ 0))
              (setf cx ix cy iy cz iz))
            (loop with t0 of-type double-float = 0d0
                  while (< t0 best)
                  do (let* ((t1 (min best (+ t0 1d0)))
                            (ax (+ ox (* t0 ux))) (bx (+ ox (* t1 ux)))
                            (ay (+ oy (* t0 uy))) (by (+ oy (* t1 uy)))
                            (az (+ oz (* t0 uz))) (bz (+ oz (* t1 uz))))
                       (loop for k of-type fixnum from (dcell (- (min az bz) r)) to (dcell (+ (max az bz) r)) do
                         (loop for j of-type fixnum from (dcell (- (min ay by) r)) to (dcell (+ (max ay by) r)) do
                           (loop for i of-type fixnum from (dcell (- (min ax bx) r)) to (dcell (+ (max ax bx) r)) do
                             (sweep-cell-if-solid i j k))))
                       (when (<= best t1) (return))
                       (setf t0 t1)))))))
  s)

(defun physics-sphere-cast (world x y z radius dx dy dz max-distance
                            &key (bodies t) (cells t) (boxes t) exclude filter hit)
  "The first thing a sphere of RADIUS moved from X Y Z along DX DY DZ meets before it has moved
MAX-DISTANCE, as physics-ray-cast answers it: the distance moved, the point of contact and the
normal out of what was met. #S9WEEP"
  (check-world world 'physics-sphere-cast)
  (physics-cast 'physics-sphere-cast world x y z radius dx dy dz max-distance bodies cells boxes exclude filter hit))
;; Spheres swept along a path:1 ends here

;; [[file:../physics.org::#OV3RLP][Bodies and cells in a region:1]]
(defmacro do-bodies-in-region ((buf row) (view world x0 y0 z0 x1 y1 z1) &body body)
  "Run BODY with BUF and ROW bound to the buffer and row of every body of VIEW, awake or asleep,
whose centre may lie in the box X0..X1 Y0..Y1 Z0..Z1 (doubles) grown by the largest radius,
each once: through the grids and the sleeping strays, or row by row when the region meets more
cells of a grid than its set has bodies. #OV3RLP"
  (let ((v (gensym "VIEW")) (w (gensym "WORLD")))
    `(let ((,v ,view) (,w ,world))
       (declare (type query-view ,v))
       ,@(loop for handles-p in '(nil t)
               collect
               (let ((grow (gensym "GROW")) (item (gensym "ITEM")) (q (gensym)) (grid (gensym "GRID")))
                 `(let* ((,buf ,(if handles-p `(physics-world-sleeping ,w) `(physics-world-awake ,w)))
                         (,grid ,(if handles-p `(query-view-sleeping-grid ,v) `(query-view-awake-grid ,v)))
                         (,grow (+ (float (the single-float (physics-world-max-radius ,w)) 1d0) 1d-4)))
                    (declare (type body-columns ,buf) (type double-float ,grow))
                    (flet ((visit (,row) (declare (type index ,row)) ,@body))
                      (declare (inline visit))
                      (if (> (grid-box-cells ,grid (- ,x0 ,grow) (- ,y0 ,grow) (- ,z0 ,grow) (+ ,x1 ,grow)
                                             (+ ,y1 ,grow) (+ ,z1 ,grow))
                             (float (body-columns-length ,buf) 1d0))
                          (dotimes (,q (body-columns-length ,buf)) (visit ,q))
                          (progn
                            (do-grid-box (,item ,grid (- ,x0 ,grow) (- ,y0 ,grow) (- ,z0 ,grow) (+ ,x1 ,grow)
                                                (+ ,y1 ,grow) (+ ,z1 ,grow))
                              (let ((,row (view-row ,v ,w ,handles-p ,item)))
                                (declare (type fixnum ,row))
                                (when (>= ,row 0) (visit ,row))))
                            ,@(when handles-p
                                `((let ((strays (query-view-sleeping-strays ,v)))
                                    (declare (type fixnum-column strays))
                                    (dotimes (,q (query-view-sleeping-stray-count ,v))
                                      (visit (aref strays ,q)))))))))))))))

(declaim (inline region-size))

(defun region-size (world name value)
  "VALUE, a radius or a half-extent, as a double, after checking it is finite and from 0 to 1024 m. #OV3RLP"
  (let ((f (finite-f32 name value world)))
    (unless (<= 0 f 1024)
      (error 'invalid-physics-parameter :world world :name name :value value :expected "from 0 to 1024 m"))
    f))

(defmacro with-region-arguments ((world function operation (&rest coordinates) (&rest sizes)) &body body)
  "Check WORLD (as every exported OPERATION does), FUNCTION, the centre COORDINATES and the SIZES of
a region query, then run BODY
with each of them bound to its value as a double, and WORLD refusing edits. The doubles are
bound inside with-world-held's unwind-protect: a double live across it would be boxed. #OV3RLP"
  (flet ((key (symbol) (intern (symbol-name symbol) '#:keyword)))
    `(progn
       (check-world ,world ',operation)
       (unless (functionp ,function)
         (error 'invalid-physics-parameter :world ,world :name :function :value ,function :expected "a function"))
       (let (,@(loop for c in coordinates
                     collect `(,c (let ((v (finite-f32 ,(key c) ,c ,world))) (check-coordinate ,(key c) v ,world) v)))
             ,@(loop for s in sizes collect `(,s (region-size ,world ,(key s) ,s))))
         (declare (type single-float ,@coordinates ,@sizes))
         (with-world-held (,world)
           (let (,@(loop for v in (append coordinates sizes) collect `(,v (float ,v 1d0))))
             (declare (type double-float ,@coordinates ,@sizes))
             ,@body))))))

(defun map-physics-bodies-in-sphere (function world x y z radius)
  "Call FUNCTION with the handle of each body of WORLD, awake or asleep, that meets the sphere of
RADIUS about X Y Z (centres no farther apart than the two radii); return how many. The world
refuses edits while FUNCTION runs. #OV3RLP"
  (with-region-arguments (world function map-physics-bodies-in-sphere (x y z) (radius))
    (let ((view (world-query-view world)) (count 0))
      (declare (type index count))
      (progn
        (do-bodies-in-region (buf row) (view world (- x radius) (- y radius) (- z radius)
                                             (+ x radius) (+ y radius) (+ z radius))
          (let* ((dx (- (float (aref (body-columns-x buf) row) 1d0) x))
                 (dy (- (float (aref (body-columns-y buf) row) 1d0) y))
                 (dz (- (float (aref (body-columns-z buf) row) 1d0) z))
                 (reach (+ radius (float (aref (body-columns-radius buf) row) 1d0))))
            (when (<= (+ (* dx dx) (* dy dy) (* dz dz)) (* reach reach))
              (incf count)
              (funcall function (aref (body-columns-handle buf) row))))))
      count)))

(defun map-physics-bodies-in-box (function world x y z hx hy hz)
  "Call FUNCTION with the handle of each body of WORLD, awake or asleep, that meets the box about
X Y Z with half-extents HX HY HZ (its nearest point of the box no farther than its radius);
return how many. The world refuses edits while FUNCTION runs. #OV3RLP"
  (with-region-arguments (world function map-physics-bodies-in-box (x y z) (hx hy hz))
    (let ((view (world-query-view world)) (count 0))
      (declare (type index count))
      (progn
        (do-bodies-in-region (buf row) (view world (- x hx) (- y hy) (- z hz) (+ x hx) (+ y hy) (+ z hz))
          (let* ((bx (float (aref (body-columns-x buf) row) 1d0))
                 (by (float (aref (body-columns-y buf) row) 1d0))
                 (bz (float (aref (body-columns-z buf) row) 1d0))
                 (dx (- bx (max (- x hx) (min (+ x hx) bx))))
                 (dy (- by (max (- y hy) (min (+ y hy) by))))
                 (dz (- bz (max (- z hz) (min (+ z hz) bz))))
                 (r (float (aref (body-columns-radius buf) row) 1d0)))
            (when (<= (+ (* dx dx) (* dy dy) (* dz dz)) (* r r))
              (incf count)
              (funcall function (aref (body-columns-handle buf) row))))))
      count)))

(defmacro do-solid-cells ((i j k) (view world x0 y0 z0 x1 y1 z1) &body body)
  "Run BODY with I J K bound to each solid cell of WORLD's terrain whose closed unit box meets the
box X0..X1 Y0..Y1 Z0..Z1 (doubles), z slowest and x fastest. #OV3RLP"
  `(when (physics-world-terrain ,world)
     (with-chunk-reader (solid-p (query-view-probe ,view))
       (loop for ,k of-type fixnum from (1- (dcell ,z0)) to (dcell ,z1) do
         (loop for ,j of-type fixnum from (1- (dcell ,y0)) to (dcell ,y1) do
           (loop for ,i of-type fixnum from (1- (dcell ,x0)) to (dcell ,x1) do
             (when (and (>= (float (1+ ,i) 1d0) ,x0) (>= (float (1+ ,j) 1d0) ,y0) (>= (float (1+ ,k) 1d0) ,z0)
                        (solid-p ,i ,j ,k))
               ,@body)))))))

(defun map-physics-cells-in-sphere (function world x y z radius)
  "Call FUNCTION with the coordinates of each solid cell of WORLD's terrain (a cell of a chunk that
is not resident is solid) within RADIUS of X Y Z; return how many. #OV3RLP"
  (with-region-arguments (world function map-physics-cells-in-sphere (x y z) (radius))
    (let ((view (world-query-view world)) (count 0))
      (declare (type index count))
      (progn
        (do-solid-cells (i j k) (view world (- x radius) (- y radius) (- z radius)
                                      (+ x radius) (+ y radius) (+ z radius))
          (let* ((dx (- x (max (float i 1d0) (min (float (1+ i) 1d0) x))))
                 (dy (- y (max (float j 1d0) (min (float (1+ j) 1d0) y))))
                 (dz (- z (max (float k 1d0) (min (float (1+ k) 1d0) z)))))
            (when (<= (+ (* dx dx) (* dy dy) (* dz dz)) (* radius radius))
              (incf count)
              (funcall function i j k)))))
      count)))

(defun map-physics-cells-in-box (function world x y z hx hy hz)
  "Call FUNCTION with the coordinates of each solid cell of WORLD's terrain (a cell of a chunk that
is not resident is solid) that meets the box about X Y Z with half-extents HX HY HZ; return how
many. #OV3RLP"
  (with-region-arguments (world function map-physics-cells-in-box (x y z) (hx hy hz))
    (let ((view (world-query-view world)) (count 0))
      (declare (type index count))
      (progn
        (do-solid-cells (i j k) (view world (- x hx) (- y hy) (- z hz) (+ x hx) (+ y hy) (+ z hz))
          (incf count)
          (funcall function i j k)))
      count)))
;; Bodies and cells in a region:1 ends here
