;;;; tools/view.lisp -- record a standard scene and write its viewer (make view SCENE=basin).
;;;; Environment: SCENE (the name of a scene of the page, default basin), EVERY (steps a frame,
;;;; default 2), VIEW (the file to write, default report/view-SCENE.html).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(defun physics (name) (find-symbol name '#:luv-physics))

(let* ((name (intern (string-upcase (or (sb-ext:posix-getenv "SCENE") "basin")) :keyword))
       (scene (handler-case (funcall (physics "FIND-PHYSICS-SCENE") name)
                (error (e)
                  (format *error-output* "view: ~A~%" e)
                  (sb-ext:exit :code 1))))
       (every (parse-integer (or (sb-ext:posix-getenv "EVERY") "2")))
       (out (or (sb-ext:posix-getenv "VIEW") (format nil "report/view-~(~A~).html" name))))
  (ensure-directories-exist out)
  (sb-ext:gc :full t)
  (let ((start (get-internal-real-time)))
    (multiple-value-bind (world recording)
        (funcall (physics "RUN-PHYSICS-SCENE") name :record t :every every)
      (declare (ignore world))
      (let ((recorded (get-internal-real-time)))
        (funcall (physics "WRITE-PHYSICS-VIEWER") recording out
                 :title (format nil "~(~A~): ~A" name (funcall (physics "PHYSICS-SCENE-TEXT") scene)))
        (let ((written (get-internal-real-time))
              (frames (funcall (physics "PHYSICS-RECORDING-FRAME-COUNT") recording)))
          (format t "~&view: ~(~A~), ~D s at 60 Hz, a frame every ~D steps: ~D frames~%"
                  name (funcall (physics "PHYSICS-SCENE-SECONDS") scene) every frames)
          (format t "~&view: run and recorded in ~,2F s, written in ~,2F s: ~A, ~,1F MB~%"
                  (/ (- recorded start) internal-time-units-per-second)
                  (/ (- written recorded) internal-time-units-per-second)
                  out (/ (with-open-file (s out) (file-length s)) 1d6))
          (format t "~&view: open file://~A in a browser~%" (namestring (truename out))))))))
