;;;; luv-physics.asd -- the systems tangled from physics.org.  Edit physics.org, not the tangled files.
;;;;
;;;; luv-physics is the engine a game loads; luv-physics/workshop, tangled from the same page, holds
;;;; its instruments (scenes, benchmarks, the report, the viewer, the campaigns, the page's tools)
;;;; and is loaded by the Makefile's targets and the claims.

(defun luv-around-compile (compile)
  "Call COMPILE, a file's compilation, after a full collection (so that a file is not compiled in a
heap still holding the garbage of the one before), with the compiler's notes muffled and what it
prints kept from the terminal; then print one line naming the file and its seconds."
  (sb-ext:gc :full t)
  (let* ((log (make-string-output-stream))
         (started (get-internal-real-time))
         (result (multiple-value-list
                  (let ((*standard-output* log) (*compile-verbose* t) (*compile-print* nil))
                    (handler-bind ((sb-ext:compiler-note #'muffle-warning))
                      (funcall compile)))))
         (text (get-output-stream-string log))
         (at (search "; compiling file \"" text))
         (file (if at
                   (subseq text (+ at 18) (position #\" text :start (+ at 18)))
                   "a file")))
    (format *error-output* "~&; luv-physics: compiled ~A in ~,1F s~%"
            (enough-namestring file (asdf:system-source-directory "luv-physics"))
            (/ (- (get-internal-real-time) started) internal-time-units-per-second))
    (values-list result)))

(defsystem "luv-physics"
  :description "Rigid spheres in a voxel world, written as the literate page physics.org."
  :depends-on ((:require "sb-simd"))
  ;; one line per file compiled: the compiler's notes are for the page's authors
  :around-compile (lambda (compile) (luv-around-compile compile))
  :serial t
  :components ((:file "tangled/physics")
               (:file "tangled/physics-simd"))
  :in-order-to ((test-op (test-op "luv-physics/tests"))))

(defsystem "luv-physics/workshop"
  :description "The engine's instruments, from the same page: scenes, benchmarks, the report, the
viewer, the fuzz and soak campaigns, the registry of anchors and the reload."
  :depends-on ("luv-physics" (:require "sb-introspect"))
  :around-compile (lambda (compile) (luv-around-compile compile))
  :components ((:file "tangled/workshop")))

(defsystem "luv-physics/tests"
  :description "The claims of physics.org, as FiveAM tests."
  :depends-on ("luv-physics/workshop" "fiveam")
  :components ((:file "tests/physics-tests"))
  :perform (test-op (o c)
             (uiop:symbol-call '#:fiveam '#:run!
                               (uiop:find-symbol* '#:claims '#:luv-physics-tests))))
