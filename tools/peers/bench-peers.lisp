;;;; tools/peers/bench-peers.lisp -- the basin in our engine, in Bullet and in ODE, side by
;;;; side (make bench-peers).
;;;;
;;;; For each ball count it measures our basin with the widest kernel family this CPU runs and
;;;; with the scalar family (measure-basin, #B3NCH5), and the widest family with two workers
;;;; (#B3NCHW), then runs the binaries of tools/peers/bullet-basin.cpp and
;;;; tools/peers/ode-basin.cpp on the same scene, and, where BOX3D_BASIN names one, the binary of
;;;; tools/peers/box3d-basin.cpp with one worker and with two, one after the other in this one run,
;;;; and prints Org tables.  The binaries are BULLET_BASIN and ODE_BASIN in the environment, else
;;;; report/peers/bullet-basin and report/peers/ode-basin; the counts are 1000, 3000 and 10000,
;;;; or those PEER_COUNTS names.

(load (merge-pathnames "../boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(defparameter *peer-counts*
  (or (ignore-errors
       (let ((env (sb-ext:posix-getenv "PEER_COUNTS")))
         (and env (mapcar #'parse-integer (uiop:split-string env :separator " ")))))
      '(1000 3000 10000))
  "The ball counts measured: those PEER_COUNTS names (\"1000 3000\"), else make bench's.")

(defparameter *peer-steps* 300 "Steps per run.")
(defparameter *peer-from* 120 "The first step timed.")
(defparameter *peer-iterations* 10 "The solver iterations of the peers (Bullet's and ODE's).")

(defun peer-binary (variable name)
  "The path the environment VARIABLE names, else report/peers/NAME in this repository."
  (let ((env (sb-ext:posix-getenv variable)))
    (if (and env (plusp (length env)))
        (pathname env)
        (merge-pathnames (format nil "report/peers/~A" name) *luv-root*))))

(defparameter *bullet-binary* (peer-binary "BULLET_BASIN" "bullet-basin")
  "The compiled tools/peers/bullet-basin.cpp.")

(defparameter *ode-binary* (peer-binary "ODE_BASIN" "ode-basin")
  "The compiled tools/peers/ode-basin.cpp.")

(defparameter *box3d-binary*
  (let ((env (sb-ext:posix-getenv "BOX3D_BASIN")))
    (and env (plusp (length env)) (probe-file env)))
  "The compiled tools/peers/box3d-basin.cpp, or NIL when Box3D was not built (make bench-peers
BOX3D_SRC=dir builds it).")

(defparameter *peer-workers* 2 "The workers of the multi-threaded rows, ours and Box3D's.")

(defun measure-our-workers (count family workers &key (from *peer-from*) (to *peer-steps*))
  "Step the basin of COUNT balls in FAMILY with WORKERS workers TO times; a plist of the mean and
median ms per step over steps FROM..TO, as measure-basin gives them."
  (let ((world (luv-physics::open-world-workers (luv-physics::make-basin-world count :kernels family) workers))
        (times '()))
    (unwind-protect
         (dotimes (i to)
           (physics:step-physics-world world)
           (when (>= i from) (push (* 1000 (luv-physics::physics-world-last-step-real-seconds world)) times)))
      (physics:close-physics-world world))
    (list :mean (/ (reduce #'+ times) (length times)) :median (luv-physics::median times))))

(defun peer-first-line (program &rest args)
  "The first line PROGRAM ARGS prints, or NIL when it cannot run or fails."
  (ignore-errors
   (let* ((out (make-string-output-stream))
          (p (sb-ext:run-program program args :search t :output out :error nil)))
     (when (zerop (sb-ext:process-exit-code p))
       (let ((text (get-output-stream-string out)))
         (subseq text 0 (or (position #\Newline text) (length text))))))))

(defun parse-key-values (line)
  "A plist of the key=value words of LINE: keywords to numbers where they read as numbers."
  (loop for word in (uiop:split-string line :separator " ")
        for eq = (position #\= word)
        when eq
          append (let ((value (subseq word (1+ eq))))
                   (list (intern (string-upcase (subseq word 0 eq)) :keyword)
                         (let ((n (ignore-errors
                                   (let ((*read-default-float-format* 'double-float)
                                         (*read-eval* nil))
                                     (read-from-string value)))))
                           (if (realp n) n value))))))

(defun measure-peer (binary tag count &key (steps *peer-steps*) (from *peer-from*))
  "Run the peer BINARY on the basin of COUNT balls; its key=value line, which starts with TAG
and a space, as a plist."
  (let* ((out (make-string-output-stream))
         (p (sb-ext:run-program (namestring binary)
                                (mapcar #'princ-to-string
                                        (list count steps from *peer-iterations*))
                                :output out :error *error-output*))
         (line (string-trim '(#\Newline) (get-output-stream-string out))))
    (unless (and (zerop (sb-ext:process-exit-code p))
                 (eql 0 (search (concatenate 'string tag " ") line)))
      (format *error-output* "~&error: ~A ~D failed (exit ~D): ~A~%"
              (namestring binary) count (sb-ext:process-exit-code p) line)
      (sb-ext:exit :code 1))
    (parse-key-values line)))

(defun measure-bullet (count)
  "Run the Bullet binary on the basin of COUNT balls; its key=value line as a plist."
  (measure-peer *bullet-binary* "bullet" count))

(defun measure-ode (count)
  "Run the ODE binary on the basin of COUNT balls; its key=value line as a plist."
  (measure-peer *ode-binary* "ode" count))

(defun measure-box3d (count workers)
  "Run the Box3D binary on the basin of COUNT balls with WORKERS workers; its key=value line as a
plist, or NIL without the binary."
  (when *box3d-binary*
    (let ((*peer-iterations* workers))
      (measure-peer *box3d-binary* "box3d" count))))

(defun our-basin-sanity (count kernels)
  "Mean and lowest centre height and the number of balls outside the interior [0,8] x [0,8] or
below the floor's top, after *PEER-STEPS* steps of the basin of COUNT balls: the world make-basin-world
builds, rebuilt here to keep the handles."
  (let* ((world (physics:make-physics-world
                 :terrain (physics:make-basin-terrain :wall-height (if (> count 3000) 30 6))
                 :kernels kernels))
         (handles (loop for i below count
                        collect (multiple-value-bind (x y z) (luv-physics::basin-spawn-point i)
                                  (physics:add-physics-body world x y z :radius 0.25 :mass 1.0
                                                                        :friction 0.6 :restitution 0.0)))))
    (dotimes (i *peer-steps*) (physics:step-physics-world world))
    (let ((sum-y 0d0) (min-y (if handles most-positive-single-float 0.0)) (escaped 0))
      (dolist (h handles)
        (multiple-value-bind (x y z) (physics:physics-body-position world h)
          (incf sum-y y)
          (setf min-y (min min-y y))
          (when (or (< x 0) (> x 8) (< z 0) (> z 8) (< y 0)) (incf escaped))))
      (values (/ sum-y count) min-y escaped))))

(defun run-peer-benchmark (&key (counts *peer-counts*) (stream *standard-output*))
  "Print the side-by-side table and the sanity table."
  (let* ((auto (car (last (luv-physics:available-kernel-families))))
         (engines (remove-duplicates (list auto :scalar) :from-end t))
         (sanity '())
         ;; a run of no balls and one step, for the precision and the space ODE's binary reports
         (ode-build (measure-peer *ode-binary* "ode" 0 :steps 1 :from 0)))
    (format stream "~&#+caption: basin, 60 Hz, all awake, one thread; ms per step over steps ~D-~D; ~
                    luv-physics (4 substeps) on SBCL ~A vs Bullet ~A (Debian's single-precision build; ~
                    btDiscreteDynamicsWorld, stepSimulation(1/60, 0), ~D solver iterations) and ODE ~A ~
                    (Debian's ~(~A~)-precision build; ~(~A~) space, dSpaceCollide, dContactApprox1 mu 0.6, ~
                    ERP 0.2, CFM 1e-5, dWorldQuickStep(1/60), ~D iterations)~:[~;, and Box3D ~
                    (built from its source, -O2, 4 substeps, its own scheduler)~]; the ~D-worker ~
                    rows on ~D workers, the rest on one; their drivers g++ -O2, ~
                    no -march=native; ~A; load ~A; ~A~%"
            *peer-from* *peer-steps* (lisp-implementation-version)
            (or (peer-first-line "pkg-config" "--modversion" "bullet") "?") *peer-iterations*
            (or (peer-first-line "pkg-config" "--modversion" "ode") "?")
            (getf ode-build :precision "?") (getf ode-build :space "?") *peer-iterations*
            *box3d-binary* *peer-workers* *peer-workers*
            (luv-physics::cpu-model-name) (luv-physics::load-average)
            (luv-physics::machine-probe))
    (format stream "~&| balls | engine               | mean ms | median ms | / Bullet (median) | / ODE (median) |~%")
    (format stream "~&|-------+----------------------+---------+-----------+-------------------+----------------|~%")
    (finish-output stream)
    (dolist (count counts)
      (let ((ours (loop for family in engines
                        collect (cons family (luv-physics::measure-basin
                                              count :kernels family
                                              :from *peer-from* :to *peer-steps*))))
            (ours-workers (measure-our-workers count auto *peer-workers*))
            (bullet (measure-bullet count))
            (ode (measure-ode count))
            (box3d (loop for workers in (list 1 *peer-workers*)
                         for m = (measure-box3d count workers)
                         when m collect (cons workers m))))
        (flet ((row (name mean median)
                 (format stream "~&| ~5D | ~20A | ~7,3F | ~9,3F | ~17,2F | ~14,2F |~%"
                         count name mean median
                         (/ median (getf bullet :median_ms)) (/ median (getf ode :median_ms)))))
          (loop for (family . m) in ours
                do (row (format nil "luv-physics ~(~A~)" family) (getf m :mean) (getf m :median)))
          (row (format nil "luv-physics ~(~A~) ~Dw" auto *peer-workers*)
               (getf ours-workers :mean) (getf ours-workers :median))
          (loop for (workers . m) in box3d
                do (row (format nil "Box3D ~D w" workers) (getf m :mean_ms) (getf m :median_ms)))
          (row (format nil "Bullet ~D iter." *peer-iterations*)
               (getf bullet :mean_ms) (getf bullet :median_ms))
          (row (format nil "ODE ~D iter." *peer-iterations*) (getf ode :mean_ms) (getf ode :median_ms)))
        (finish-output stream)
        (push (list count ours bullet ode box3d) sanity)))
    ;; where the piles ended: an untimed run of ours (widest family) next to the peers' own figures
    (format stream "~&~%#+caption: after ~D steps: contacts in the last step (ours: contact ~
                    constraints; Bullet: points in its manifolds, and the manifolds; ODE: contact ~
                    joints), mean and lowest ball centre height, balls outside the interior ~
                    [0,8]x[0,8] or below the floor~%"
            *peer-steps*)
    (format stream "~&| balls | engine               | contacts | manifolds | mean y m | min y m | escaped |~%")
    (format stream "~&|-------+----------------------+----------+-----------+----------+---------+---------|~%")
    (dolist (entry (reverse sanity))
      (destructuring-bind (count ours bullet ode box3d) entry
        (multiple-value-bind (mean-y min-y escaped) (our-basin-sanity count auto)
          (format stream "~&| ~5D | ~20A | ~8D | ~9A | ~8,3F | ~7,3F | ~7D |~%"
                  count (format nil "luv-physics ~(~A~)" auto)
                  (getf (cdr (assoc auto ours)) :contacts) "" mean-y min-y escaped))
        (format stream "~&| ~5D | ~20A | ~8D | ~9D | ~8,3F | ~7,3F | ~7D |~%"
                count (format nil "Bullet ~D iter." *peer-iterations*)
                (getf bullet :points) (getf bullet :manifolds)
                (getf bullet :mean_y) (getf bullet :min_y) (getf bullet :escaped))
        (format stream "~&| ~5D | ~20A | ~8D | ~9A | ~8,3F | ~7,3F | ~7D |~%"
                count (format nil "ODE ~D iter." *peer-iterations*) (getf ode :contacts) ""
                (getf ode :mean_y) (getf ode :min_y) (getf ode :escaped))
        (loop for (workers . m) in box3d
              do (format stream "~&| ~5D | ~20A | ~8D | ~9A | ~8,3F | ~7,3F | ~7D |~%"
                         count (format nil "Box3D ~D w" workers) (getf m :contacts) ""
                         (getf m :mean_y) (getf m :min_y) (getf m :escaped)))
        (finish-output stream)))))

(run-peer-benchmark)
