;;;; tools/joint-grid-one.lisp -- one process of make bench-joint-grid (physics.org, #J0GR1D): load
;;;; the engine of the tree ROOT and print, for each kernel family, one line
;;;;   joint-grid FAMILY MS CORNER-Y
;;;; this thread's CPU time per step, in ms, over STEPS steps of Box3D's joint grid of N x N
;;;; spheres (joint-grid-world), and the height of its lowest corner's centre at the end.
;;;;
;;;; Usage: sbcl --script tools/joint-grid-one.lisp ROOT/ FAMILIES N STEPS   (FAMILIES as scalar,avx2)

(load (merge-pathnames "one-process.lisp" *load-truename*))

(defvar *joint-grid-arguments* (one-process-arguments "joint-grid-one" "ROOT/ FAMILIES N STEPS" 4))

(defun joint-grid-cpu-ns ()
  "This thread's CPU time in nanoseconds."
  (multiple-value-bind (seconds nanoseconds) (sb-unix::clock-gettime sb-unix:clock-thread-cputime-id)
    (+ (* seconds 1000000000) nanoseconds)))

(destructuring-bind (root families n steps) *joint-grid-arguments*
  (declare (ignore root))
  (let ((n (parse-integer n)) (steps (parse-integer steps)))
    (dolist (name (uiop:split-string families :separator ","))
      (let ((family (intern (string-upcase name) :keyword)))
        (multiple-value-bind (world corner) (funcall (find-symbol "JOINT-GRID-WORLD" :luv-physics) n :kernels family)
          (let ((start (joint-grid-cpu-ns)))
            (dotimes (i steps) (funcall (find-symbol "STEP-PHYSICS-WORLD" :luv-physics) world))
            (format t "~&joint-grid ~(~A~) ~,4F ~,4F~%" family (/ (- (joint-grid-cpu-ns) start) 1d6 steps)
                    (nth-value 1 (funcall (find-symbol "PHYSICS-BODY-POSITION" :luv-physics) world corner)))
            (finish-output)))))))
